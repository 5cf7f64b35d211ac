#pragma once
/// SerialPort: a real tty (USB CDC, UART or pseudo-terminal) opened with plain termios: raw 8N1,
/// non-blocking, exclusive (TIOCEXCL plus an advisory flock), I/O through poll() with timeouts, the
/// previous settings restored on close. Errors at open name the cause and the fix.

#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>

#include <termios.h>

namespace graspbed::hardware {

/// Why a port could not be opened.
enum class PortErrorKind { kMissing, kPermission, kBusy, kNotATty, kBadBaud, kOther };

/// A port that cannot be used; what() says which port, why, and what to do.
class PortError : public std::runtime_error {
 public:
  PortError(PortErrorKind kind, const std::string& message) : std::runtime_error(message), kind_(kind) {}
  PortErrorKind kind() const { return kind_; }

 private:
  PortErrorKind kind_;
};

/// Outcome of one Read()/Write().
enum class IoStatus {
  kOk,       ///< some bytes moved (possibly 0 when woken)
  kTimeout,  ///< nothing within the timeout
  kHangup,   ///< the device went away (read 0, EIO, POLLHUP/POLLERR)
  kError,    ///< another I/O error (errno in the message of the caller's choice)
};

struct IoResult {
  IoStatus status = IoStatus::kOk;
  size_t bytes = 0;    ///< bytes read or written
  bool woken = false;  ///< Read(): the wake fd became readable (and was drained)
};

/// True when `baud` is a rate termios can set (9600 .. 4000000, standard values).
bool IsSupportedBaud(int baud);

class SerialPort {
 public:
  SerialPort() = default;
  ~SerialPort();
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  /// Opens and configures `path` at `baud` [bit/s]. Throws PortError: kMissing (no such file),
  /// kPermission (names the device's group to join, e.g. dialout), kBusy (another program holds it),
  /// kNotATty, kBadBaud.
  void Open(const std::string& path, int baud);
  /// Restores the settings found at Open(), releases the lock, closes. Safe to call twice.
  void Close();
  bool is_open() const { return fd_ >= 0; }
  const std::string& path() const { return path_; }
  int fd() const { return fd_; }

  /// Waits up to `timeout_ms` for bytes (or for `wake_fd`, an eventfd, to become readable) and reads
  /// what is there into `buffer`. Never blocks longer than the timeout.
  IoResult Read(std::span<uint8_t> buffer, int timeout_ms, int wake_fd = -1);
  /// Writes all of `data`, waiting up to `timeout_ms` in total for room in the output queue.
  /// Returns kTimeout with the bytes written so far when the queue stays full.
  IoResult Write(std::span<const uint8_t> data, int timeout_ms);
  /// Waits up to `timeout_ms` for the output queue to drain (tcdrain with a deadline).
  void Drain(int timeout_ms);

 private:
  int fd_ = -1;
  std::string path_;
  termios saved_{};
  bool saved_valid_ = false;
};

/// The message for a permission error on `path` (names its group and the usermod command).
std::string PermissionMessage(const std::string& path);

}  // namespace graspbed::hardware
