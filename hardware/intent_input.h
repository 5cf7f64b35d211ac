#pragma once
/// IntentInput: the user's grasp intent, live, at the bench: keys on the terminal (c close, o open,
/// i idle, q quit; stdin in non-canonical mode while it is a terminal, restored at the end), lines
/// on stdin when it is not a terminal ("close", "open", "idle", "quit"), and lines on a FIFO for an
/// EMG pipeline or a button box (`echo close > PATH`). A thread of its own reads them; the control
/// loop takes them with Poll(), which never blocks and never allocates. Every command is kept with
/// the time it was received, for the run's output.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <termios.h>

namespace graspbed::hardware {

/// What the user asked for.
enum class IntentCommand { kClose, kOpen, kIdle, kQuit };

/// "close", "open", "idle", "quit".
const char* IntentCommandName(IntentCommand command);

/// One command as received.
struct IntentInputEvent {
  IntentCommand command = IntentCommand::kIdle;
  std::string source;       ///< "key", "stdin" or "fifo"
  double received_s = 0.0;  ///< on the clock given to Start() [s]
};

struct IntentInputConfig {
  bool read_stdin = true;  ///< keys (terminal) or lines (pipe, file) on standard input
  std::string fifo_path;   ///< "" = none; created (mode 0600) when it does not exist
};

class IntentInput {
 public:
  /// Commands kept per session (a person or a 10 Hz EMG classifier for well over an hour).
  static constexpr size_t kMaxEvents = 65536;

  /// Opens the FIFO (creating it) and, when stdin is a terminal, puts it in non-canonical mode
  /// without echo (Ctrl-C still signals). Throws std::invalid_argument naming the path when the
  /// FIFO cannot be made or opened, or the path exists and is no FIFO.
  explicit IntentInput(IntentInputConfig config);
  /// Stops the reader and restores the terminal.
  ~IntentInput();
  IntentInput(const IntentInput&) = delete;
  IntentInput& operator=(const IntentInput&) = delete;

  /// Starts the reader thread; times are seconds since `start`.
  void Start(std::chrono::steady_clock::time_point start);
  /// Stops the reader thread (joins); safe to call twice. Restores the terminal.
  void Stop();

  /// The next command not yet taken, if any: true, with the command and its index in events().
  /// Loop thread only; never blocks, never allocates (the event store is reserved up front and
  /// commands beyond kMaxEvents are counted in overflows(), not stored).
  bool Poll(IntentCommand* command, size_t* event_index);
  /// Every command received so far (a copy; not for the loop).
  std::vector<IntentInputEvent> events() const;
  /// Commands that arrived after kMaxEvents were stored (ignored).
  uint64_t overflows() const { return overflows_.load(); }
  /// Whether stdin is read as keys (a terminal) rather than lines.
  bool keys() const { return terminal_; }

 private:
  void Run();
  void Handle(const std::string& word, const char* source);

  IntentInputConfig config_;
  int stdin_fd_ = -1;
  int fifo_fd_ = -1;
  int wake_pipe_[2] = {-1, -1};
  bool terminal_ = false;
  bool terminal_saved_ = false;
  termios saved_termios_{};
  std::chrono::steady_clock::time_point start_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  mutable std::mutex mutex_;              ///< guards events_ against events()'s copy
  std::vector<IntentInputEvent> events_;  ///< reserved to kMaxEvents: never reallocated
  std::atomic<size_t> published_{0};      ///< entries of events_ complete and readable by Poll()
  std::atomic<uint64_t> overflows_{0};
  size_t taken_ = 0;  ///< loop thread only
};

}  // namespace graspbed::hardware
