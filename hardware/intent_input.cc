#include "hardware/intent_input.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace graspbed::hardware {
namespace {

std::string Trim(const std::string& text) {
  size_t begin = 0;
  size_t end = text.size();
  while (begin < end && std::isspace(static_cast<unsigned char>(text[begin]))) ++begin;
  while (end > begin && std::isspace(static_cast<unsigned char>(text[end - 1]))) --end;
  return text.substr(begin, end - begin);
}

bool ParseCommand(const std::string& word, IntentCommand* command) {
  if (word == "close" || word == "c")
    *command = IntentCommand::kClose;
  else if (word == "open" || word == "o")
    *command = IntentCommand::kOpen;
  else if (word == "idle" || word == "i")
    *command = IntentCommand::kIdle;
  else if (word == "quit" || word == "q")
    *command = IntentCommand::kQuit;
  else
    return false;
  return true;
}

}  // namespace

const char* IntentCommandName(IntentCommand command) {
  switch (command) {
    case IntentCommand::kClose:
      return "close";
    case IntentCommand::kOpen:
      return "open";
    case IntentCommand::kIdle:
      return "idle";
    case IntentCommand::kQuit:
      return "quit";
  }
  return "idle";
}

IntentInput::IntentInput(IntentInputConfig config) : config_(std::move(config)) {
  events_.reserve(kMaxEvents);
  if (!config_.fifo_path.empty()) {
    struct stat info {};
    if (::stat(config_.fifo_path.c_str(), &info) != 0) {
      if (::mkfifo(config_.fifo_path.c_str(), 0600) != 0) {
        throw std::invalid_argument("--intent-fifo " + config_.fifo_path + ": cannot create the FIFO (" +
                                    std::strerror(errno) + ")");
      }
    } else if (!S_ISFIFO(info.st_mode)) {
      throw std::invalid_argument("--intent-fifo " + config_.fifo_path + ": exists and is not a FIFO");
    }
    // Read and write: the FIFO then never reports end-of-file when a writer closes, so one writer
    // after another (each `echo close > PATH`) is read without reopening.
    fifo_fd_ = ::open(config_.fifo_path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fifo_fd_ < 0) {
      throw std::invalid_argument("--intent-fifo " + config_.fifo_path + ": cannot open (" +
                                  std::strerror(errno) + ")");
    }
  }
  if (config_.read_stdin) {
    stdin_fd_ = STDIN_FILENO;
    terminal_ = ::isatty(stdin_fd_) == 1;
    if (terminal_ && ::tcgetattr(stdin_fd_, &saved_termios_) == 0) {
      termios raw = saved_termios_;
      raw.c_lflag &= ~static_cast<tcflag_t>(ICANON | ECHO);  // keys one by one, unechoed; ISIG stays
      raw.c_cc[VMIN] = 1;
      raw.c_cc[VTIME] = 0;
      terminal_saved_ = ::tcsetattr(stdin_fd_, TCSANOW, &raw) == 0;
    }
  }
  if (::pipe2(wake_pipe_, O_CLOEXEC | O_NONBLOCK) != 0) {
    if (fifo_fd_ >= 0) ::close(fifo_fd_);
    throw std::runtime_error(std::string("intent input: pipe: ") + std::strerror(errno));
  }
}

IntentInput::~IntentInput() {
  Stop();
  if (fifo_fd_ >= 0) ::close(fifo_fd_);
  for (int fd : wake_pipe_) {
    if (fd >= 0) ::close(fd);
  }
}

void IntentInput::Start(std::chrono::steady_clock::time_point start) {
  start_ = start;
  if (!thread_.joinable()) thread_ = std::thread([this] { Run(); });
}

void IntentInput::Stop() {
  if (thread_.joinable()) {
    stop_ = true;
    const char byte = 0;
    [[maybe_unused]] const ssize_t written = ::write(wake_pipe_[1], &byte, 1);
    thread_.join();
  }
  if (terminal_saved_) {
    ::tcsetattr(stdin_fd_, TCSANOW, &saved_termios_);
    terminal_saved_ = false;
  }
}

bool IntentInput::Poll(IntentCommand* command, size_t* event_index) {
  if (taken_ >= published_.load(std::memory_order_acquire)) return false;
  *event_index = taken_;
  *command = events_[taken_].command;
  ++taken_;
  return true;
}

std::vector<IntentInputEvent> IntentInput::events() const {
  std::lock_guard lock(mutex_);
  return {events_.begin(), events_.begin() + static_cast<std::ptrdiff_t>(published_.load())};
}

void IntentInput::Handle(const std::string& word, const char* source) {
  IntentCommand command;
  const std::string text = Trim(word);
  if (text.empty()) return;
  if (!ParseCommand(text, &command)) {
    std::fprintf(stderr, "intent: '%s' from %s ignored (close, open, idle or quit)\n", text.c_str(), source);
    return;
  }
  const double received_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  {
    std::lock_guard lock(mutex_);
    if (events_.size() >= kMaxEvents) {
      overflows_.fetch_add(1);
      return;
    }
    events_.push_back({command, source, received_s});
    published_.store(events_.size(), std::memory_order_release);
  }
  // Said back at once, so the person at the bench sees that the hand got it.
  std::fprintf(stderr, "intent: %s (%s) at %.3f s\n", IntentCommandName(command), source, received_s);
}

void IntentInput::Run() {
  std::string stdin_line;
  std::string fifo_line;
  bool stdin_open = stdin_fd_ >= 0;
  char buffer[256];
  while (!stop_.load()) {
    pollfd fds[3];
    nfds_t count = 0;
    fds[count++] = {wake_pipe_[0], POLLIN, 0};
    const nfds_t stdin_slot = stdin_open ? count : 99;
    if (stdin_open) fds[count++] = {stdin_fd_, POLLIN, 0};
    const nfds_t fifo_slot = fifo_fd_ >= 0 ? count : 99;
    if (fifo_fd_ >= 0) fds[count++] = {fifo_fd_, POLLIN, 0};
    if (::poll(fds, count, -1) < 0) {
      if (errno == EINTR) continue;
      return;
    }
    if (fds[0].revents != 0) return;  // Stop()
    if (stdin_slot != 99 && fds[stdin_slot].revents != 0) {
      const ssize_t n = ::read(stdin_fd_, buffer, sizeof(buffer));
      if (n <= 0) {
        stdin_open = false;  // end of input (a closed pipe, /dev/null): the other sources go on
      } else if (terminal_) {
        for (ssize_t k = 0; k < n; ++k) {
          const char key = static_cast<char>(std::tolower(static_cast<unsigned char>(buffer[k])));
          if (key == 'c' || key == 'o' || key == 'i' || key == 'q') Handle(std::string(1, key), "key");
        }
      } else {
        stdin_line.append(buffer, static_cast<size_t>(n));
        for (size_t end; (end = stdin_line.find('\n')) != std::string::npos;) {
          Handle(stdin_line.substr(0, end), "stdin");
          stdin_line.erase(0, end + 1);
        }
      }
    }
    if (fifo_slot != 99 && fds[fifo_slot].revents != 0) {
      const ssize_t n = ::read(fifo_fd_, buffer, sizeof(buffer));
      if (n > 0) {
        fifo_line.append(buffer, static_cast<size_t>(n));
        for (size_t end; (end = fifo_line.find('\n')) != std::string::npos;) {
          Handle(fifo_line.substr(0, end), "fifo");
          fifo_line.erase(0, end + 1);
        }
      }
    }
  }
}

}  // namespace graspbed::hardware
