#include "hardware/serial_port.h"

#include <cerrno>
#include <chrono>
#include <cstring>

#include <fcntl.h>
#include <grp.h>
#include <poll.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace graspbed::hardware {
namespace {

struct BaudEntry {
  int baud;
  speed_t speed;
};
constexpr BaudEntry kBauds[] = {
    {9600, B9600},       {19200, B19200},     {38400, B38400},     {57600, B57600},     {115200, B115200},
    {230400, B230400},   {460800, B460800},   {500000, B500000},   {576000, B576000},   {921600, B921600},
    {1000000, B1000000}, {1152000, B1152000}, {1500000, B1500000}, {2000000, B2000000}, {2500000, B2500000},
    {3000000, B3000000}, {3500000, B3500000}, {4000000, B4000000},
};

std::string Errno(int error) { return std::strerror(error); }

}  // namespace

bool IsSupportedBaud(int baud) {
  for (const auto& entry : kBauds) {
    if (entry.baud == baud) return true;
  }
  return false;
}

std::string PermissionMessage(const std::string& path) {
  std::string group_name = "dialout";
  struct stat info {};
  if (stat(path.c_str(), &info) == 0) {
    if (const struct group* g = getgrgid(info.st_gid); g != nullptr && g->gr_name != nullptr) {
      group_name = g->gr_name;
    } else {
      group_name = std::to_string(info.st_gid);
    }
  }
  return "serial port " + path + ": permission denied; the device belongs to group '" + group_name +
         "': join it with `sudo usermod -aG " + group_name + " $USER` and log in again";
}

SerialPort::~SerialPort() { Close(); }

void SerialPort::Open(const std::string& path, int baud) {
  Close();
  speed_t speed = 0;
  bool found = false;
  for (const auto& entry : kBauds) {
    if (entry.baud == baud) {
      speed = entry.speed;
      found = true;
    }
  }
  if (!found) {
    throw PortError(PortErrorKind::kBadBaud,
                    "serial port " + path + ": baud = " + std::to_string(baud) + ": not a supported rate");
  }
  const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int error = errno;
    switch (error) {
      case ENOENT:
      case ENXIO:
      case ENODEV:
        throw PortError(PortErrorKind::kMissing,
                        "serial port " + path + " does not exist (" + Errno(error) +
                            "): is the device plugged in and the path right? (for the emulator, start "
                            "`graspbed emulate --link " +
                            path + "` first)");
      case EACCES:
      case EPERM:
        throw PortError(PortErrorKind::kPermission, PermissionMessage(path));
      case EBUSY:
        throw PortError(PortErrorKind::kBusy, "serial port " + path +
                                                  " is busy: another program holds it exclusively "
                                                  "(find it with `fuser " +
                                                  path + "`)");
      default:
        throw PortError(PortErrorKind::kOther, "serial port " + path + ": open failed: " + Errno(error));
    }
  }
  auto fail = [&](PortErrorKind kind, const std::string& message) {
    ::close(fd);
    throw PortError(kind, "serial port " + path + ": " + message);
  };
  if (!isatty(fd)) fail(PortErrorKind::kNotATty, "not a terminal device");
  // TIOCEXCL stops further opens (except by root); the flock also catches a second graspbed or any
  // tool that honours advisory locks, root or not.
  if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
    fail(PortErrorKind::kBusy, "busy: another program has it open (find it with `fuser " + path + "`)");
  }
  termios saved{};
  if (tcgetattr(fd, &saved) != 0) fail(PortErrorKind::kOther, "tcgetattr failed: " + Errno(errno));
  termios raw = saved;
  cfmakeraw(&raw);
  raw.c_cflag |= CLOCAL | CREAD;
  raw.c_cflag &= ~(CSTOPB | CRTSCTS);
  raw.c_cc[VMIN] = 0;
  raw.c_cc[VTIME] = 0;
  cfsetispeed(&raw, speed);
  cfsetospeed(&raw, speed);
  if (tcsetattr(fd, TCSANOW, &raw) != 0) fail(PortErrorKind::kOther, "tcsetattr failed: " + Errno(errno));
  ioctl(fd, TIOCEXCL);
  tcflush(fd, TCIOFLUSH);  // bytes queued before we came are of no session of ours
  fd_ = fd;
  path_ = path;
  saved_ = saved;
  saved_valid_ = true;
}

void SerialPort::Close() {
  if (fd_ < 0) return;
  ioctl(fd_, TIOCNXCL);
  if (saved_valid_) tcsetattr(fd_, TCSANOW, &saved_);  // may fail on a vanished device: nothing to restore
  flock(fd_, LOCK_UN);
  ::close(fd_);
  fd_ = -1;
  saved_valid_ = false;
}

IoResult SerialPort::Read(std::span<uint8_t> buffer, int timeout_ms, int wake_fd) {
  IoResult result;
  if (fd_ < 0) return {IoStatus::kHangup, 0, false};
  pollfd fds[2] = {{fd_, POLLIN, 0}, {wake_fd, POLLIN, 0}};
  const int count = ::poll(fds, wake_fd >= 0 ? 2 : 1, timeout_ms);
  if (count < 0) {
    if (errno == EINTR) return {IoStatus::kTimeout, 0, false};
    return {IoStatus::kError, 0, false};
  }
  if (wake_fd >= 0 && (fds[1].revents & POLLIN)) {
    uint64_t value = 0;
    [[maybe_unused]] const ssize_t drained = ::read(wake_fd, &value, sizeof(value));
    result.woken = true;
  }
  if (fds[0].revents & POLLIN) {
    const ssize_t n = ::read(fd_, buffer.data(), buffer.size());
    if (n > 0) {
      result.bytes = static_cast<size_t>(n);
      return result;
    }
    if (n == 0) return {IoStatus::kHangup, 0, result.woken};
    if (errno == EAGAIN || errno == EINTR) return result;
    return {errno == EIO ? IoStatus::kHangup : IoStatus::kError, 0, result.woken};
  }
  if (fds[0].revents & (POLLHUP | POLLERR | POLLNVAL)) return {IoStatus::kHangup, 0, result.woken};
  if (count == 0) result.status = IoStatus::kTimeout;
  return result;
}

IoResult SerialPort::Write(std::span<const uint8_t> data, int timeout_ms) {
  IoResult result;
  if (fd_ < 0) return {IoStatus::kHangup, 0, false};
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (result.bytes < data.size()) {
    const ssize_t n = ::write(fd_, data.data() + result.bytes, data.size() - result.bytes);
    if (n > 0) {
      result.bytes += static_cast<size_t>(n);
      continue;
    }
    if (n < 0 && errno != EAGAIN && errno != EINTR) {
      result.status = errno == EIO ? IoStatus::kHangup : IoStatus::kError;
      return result;
    }
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      result.status = IoStatus::kTimeout;
      return result;
    }
    pollfd fd{fd_, POLLOUT, 0};
    if (::poll(&fd, 1, static_cast<int>(left.count())) > 0 && (fd.revents & (POLLHUP | POLLERR))) {
      result.status = IoStatus::kHangup;
      return result;
    }
  }
  return result;
}

void SerialPort::Drain(int timeout_ms) {
  if (fd_ < 0) return;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (std::chrono::steady_clock::now() < deadline) {
    int queued = 0;
    if (ioctl(fd_, TIOCOUTQ, &queued) != 0 || queued == 0) return;
    usleep(500);
  }
}

}  // namespace graspbed::hardware
