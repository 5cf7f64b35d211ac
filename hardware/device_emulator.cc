#include "hardware/device_emulator.h"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <vector>

#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include "common/config_error.h"

namespace graspbed::hardware {
namespace {

int64_t NowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

int64_t SecondsToNs(double s) { return static_cast<int64_t>(std::llround(s * 1e9)); }

}  // namespace

void EmulatorConfig::Validate() const {
  using common::Require;
  if (link_path.empty()) throw common::ConfigError("", 0, "emulator.link_path", "\"\"", "must not be empty");
  Require(unit_count >= 1 && unit_count <= kMaxUnitsOnWire, "emulator.unit_count", unit_count,
          "must be in 1..62 (512-byte packets)");
  Require(frame_rate_hz >= 1 && frame_rate_hz <= 10000, "emulator.frame_rate_hz", frame_rate_hz,
          "must be in 1..10000");
  Require(hello_period_s > 0, "emulator.hello_period_s", hello_period_s, "must be > 0");
  Require(connect_delay_s >= 0, "emulator.connect_delay_s", connect_delay_s, "must be >= 0");
  Require(watchdog_s > 0, "emulator.watchdog_s", watchdog_s, "must be > 0");
  Require(nominal_r0_ohm > 0, "emulator.nominal_r0_ohm", nominal_r0_ohm, "must be > 0");
  Require(protocol_version >= 1 && protocol_version <= kProtocolVersion, "emulator.protocol_version",
          protocol_version, "must be 1 or 2");
}

DeviceEmulator::DeviceEmulator(const EmulatorConfig& config, FrameSource source, MotorSink sink)
    : config_(config), source_(std::move(source)), sink_(std::move(sink)) {
  config_.Validate();
  if (!source_) throw std::invalid_argument("emulator: no frame source");
}

DeviceEmulator::~DeviceEmulator() { Stop(); }

void DeviceEmulator::OpenPty() {
  int master = -1;
  int slave = -1;
  char name[256] = {};
  if (openpty(&master, &slave, name, nullptr, nullptr) != 0) {
    throw std::runtime_error(std::string("emulator: openpty failed: ") + std::strerror(errno));
  }
  // Raw before any host opens it: a cooked slave would echo our HELLOs back to us.
  termios raw{};
  tcgetattr(slave, &raw);
  cfmakeraw(&raw);
  tcsetattr(slave, TCSANOW, &raw);
  // Without a slave open the master polls POLLHUP; that is how host connects and leaves are seen.
  ::close(slave);
  fcntl(master, F_SETFL, fcntl(master, F_GETFL) | O_NONBLOCK);
  fcntl(master, F_SETFD, FD_CLOEXEC);
  struct stat info {};
  if (lstat(config_.link_path.c_str(), &info) == 0) {
    if (!S_ISLNK(info.st_mode)) {
      ::close(master);
      throw std::runtime_error("emulator: " + config_.link_path +
                               " exists and is not a symlink; refusing to replace it");
    }
    ::unlink(config_.link_path.c_str());
  }
  if (symlink(name, config_.link_path.c_str()) != 0) {
    const int error = errno;
    ::close(master);
    throw std::runtime_error("emulator: cannot create symlink " + config_.link_path + ": " +
                             std::strerror(error));
  }
  master_fd_ = master;
  slave_path_ = name;
  symlink_made_ = true;
  decoder_.Reset();
  out_size_ = 0;
  held_size_ = 0;
  hellos_this_connection_ = 0;
  answers_this_connection_ = 0;
  selected_version_ = 1;
  stats_.host_connected = false;
  stats_.streaming = false;
}

void DeviceEmulator::ClosePty() {
  if (symlink_made_) {
    // Only remove the link if it is still ours.
    char target[256] = {};
    const ssize_t n = readlink(config_.link_path.c_str(), target, sizeof(target) - 1);
    if (n > 0 && slave_path_ == std::string(target, static_cast<size_t>(n)))
      ::unlink(config_.link_path.c_str());
    symlink_made_ = false;
  }
  if (master_fd_ >= 0) ::close(master_fd_);
  master_fd_ = -1;
  slave_path_.clear();
  out_size_ = 0;
  held_size_ = 0;  // a held-back frame goes with the queue
  if (stats_.host_connected || motor_.enable) SetMotor({});
  stats_.host_connected = false;
  stats_.streaming = false;
}

void DeviceEmulator::Start() {
  if (running_) return;
  {
    std::lock_guard lock(mutex_);
    OpenPty();
  }
  running_ = true;
  thread_ = std::thread([this] { Run(); });
}

void DeviceEmulator::Stop() {
  if (running_.exchange(false) && thread_.joinable()) thread_.join();
  std::lock_guard lock(mutex_);
  ClosePty();
}

void DeviceEmulator::SetMotor(const EmulatedMotor& motor) {
  motor_ = motor;
  if (sink_) sink_(motor_);
}

bool DeviceEmulator::Queue(std::span<const uint8_t> bytes) {
  // Host not reading: drop the whole packet, as a full USB FIFO would (never a part of one).
  if (out_size_ + bytes.size() > out_.size()) return false;
  std::copy(bytes.begin(), bytes.end(), out_.begin() + static_cast<long>(out_size_));
  out_size_ += bytes.size();
  return true;
}

void DeviceEmulator::SendFrame(std::span<const uint8_t> bytes, uint64_t index, bool intact) {
  if (!Queue(bytes)) {
    ++stats_.frames_overflowed;
    return;
  }
  ++stats_.frames_sent;
  if (!intact) return;
  if (newest_intact_valid_ && index < newest_intact_index_) {
    ++stats_.frames_reordered;  // a newer intact frame went before it: the host sees it late
  } else {
    newest_intact_valid_ = true;
    newest_intact_index_ = index;
  }
}

void DeviceEmulator::ReleaseHeld() {
  if (held_size_ == 0) return;
  SendFrame(std::span<const uint8_t>(held_.data(), held_size_), held_index_, /*intact=*/true);
  held_size_ = 0;
}

void DeviceEmulator::QueueHello() {
  HelloPacket hello;
  hello.sequence = hello_seq_++;
  hello.firmware_version = config_.firmware_version;
  hello.unit_count = static_cast<uint8_t>(config_.unit_count);
  // A version-1 device leaves byte 7 reserved (0).
  hello.max_version = config_.protocol_version >= 2 ? static_cast<uint8_t>(config_.protocol_version) : 0;
  hello.nominal_rate_hz = static_cast<uint16_t>(config_.frame_rate_hz);
  hello.nominal_r0_milliohm = OhmToMilliohm(config_.nominal_r0_ohm);
  std::array<uint8_t, kMaxWirePacketSize> out;
  if (!Queue(std::span<const uint8_t>(out.data(), EncodePacket(hello, out)))) return;  // FIFO full
  ++stats_.hellos_sent;
  ++hellos_this_connection_;
  hello_sent_this_connection_ = true;
}

void DeviceEmulator::Flush() {
  if (master_fd_ < 0 || out_size_ == 0) return;
  const ssize_t n = ::write(master_fd_, out_.data(), out_size_);
  if (n <= 0) return;  // EAGAIN: the host is not reading; try again next tick
  std::memmove(out_.data(), out_.data() + n, out_size_ - static_cast<size_t>(n));
  out_size_ -= static_cast<size_t>(n);
}

void DeviceEmulator::HandleHostPacket(const DecodedPacket& packet, int64_t now_ns) {
  if (!hello_sent_this_connection_) ++stats_.commands_before_hello;
  switch (packet.type) {
    case PacketType::kMotorCommand: {
      ++stats_.motor_commands;
      if (last_command_enabled_) {  // the watchdog was armed since the previous command
        stats_.max_command_interval_s =
            std::max(stats_.max_command_interval_s, static_cast<double>(now_ns - last_motor_ns_) * 1e-9);
      }
      last_motor_ns_ = now_ns;
      EmulatedMotor motor;
      motor.enable = (packet.motor.flags & kMotorEnable) != 0;
      motor.brake = (packet.motor.flags & kMotorBrake) != 0;
      motor.effort = motor.enable ? EffortFromWire(packet.motor.effort) : 0.0;
      if (!motor.enable) ++stats_.motor_off_commands;
      last_command_enabled_ = motor.enable;
      SetMotor(motor);
      break;
    }
    case PacketType::kStreamControl:
      if (packet.stream.start) {
        ++stats_.stream_starts;
        ++answers_this_connection_;  // the host answers every HELLO it decodes with a start
        stats_.streaming = true;
      } else {
        ++stats_.stream_stops;
        stats_.streaming = false;
      }
      break;
    case PacketType::kProtocolSelect:
      // A version-1 device does not know this type: it ignores (and counts) it.
      if (config_.protocol_version < kHandProtocolVersion || packet.select.version < 1 ||
          packet.select.version > config_.protocol_version) {
        ++stats_.host_unknown;
        break;
      }
      selected_version_ = packet.select.version;
      ++stats_.selects;
      break;
    case PacketType::kTactileFrame:
    case PacketType::kHello:
    case PacketType::kHand:
      break;  // device-to-host types: a confused host; ignore
  }
}

void DeviceEmulator::SendHand(double device_time_s, uint32_t device_time_us) {
  if (selected_version_ < kHandProtocolVersion || !hand_source_) return;
  if (!hand_source_(device_time_s, &hand_state_) || hand_state_.digit_count < 1) return;
  const uint16_t sequence = hand_seq_++;
  if (drop_hand_ > 0) {
    --drop_hand_;
    ++stats_.hand_dropped;
    return;
  }
  FromHandState(hand_state_, sequence, device_time_us, &wire_hand_);
  std::array<uint8_t, kMaxWirePacketSize> out;
  size_t size = 0;
  if (malformed_hand_ > 0) {
    // A valid CRC around a body that claims 3 digits and carries them: refused for its digit count.
    std::array<uint8_t, HandBodySize(3)> body{};
    body[0] = static_cast<uint8_t>(PacketType::kHand);
    body[1] = kHandProtocolVersion;
    body[2] = static_cast<uint8_t>(sequence);
    body[3] = static_cast<uint8_t>(sequence >> 8);
    body[8] = 3;
    size = EncodeBody(body, out);
  } else {
    size = EncodePacket(wire_hand_, out);
  }
  if (size == 0) return;
  const bool corrupt = corrupt_hand_ > 0 && malformed_hand_ == 0;
  if (corrupt) {
    uint8_t& byte = out[size / 2];
    byte = (byte ^ 0x5A) != 0 ? static_cast<uint8_t>(byte ^ 0x5A) : static_cast<uint8_t>(byte ^ 0xA5);
  }
  if (!Queue(std::span<const uint8_t>(out.data(), size))) {
    ++stats_.hand_overflowed;  // a pending fault waits for a HAND that is sent
    return;
  }
  ++stats_.hand_sent;
  if (malformed_hand_ > 0) {
    --malformed_hand_;
    ++stats_.hand_malformed;
  } else if (corrupt) {
    --corrupt_hand_;
    ++stats_.hand_corrupted;
  }
}

void DeviceEmulator::CheckWatchdog(int64_t now_ns) {
  // The motor watchdog runs whether or not a host is there.
  if (motor_.enable && now_ns - last_motor_ns_ > SecondsToNs(config_.watchdog_s)) {
    ++stats_.watchdog_trips;
    SetMotor({});
  }
}

void DeviceEmulator::Tick(int64_t now_ns) {
  ++tick_;
  const double period_s = 1.0 / config_.frame_rate_hz;
  const uint64_t device_tick = tick_ - time_base_tick_;
  const double device_time_s = static_cast<double>(device_tick) * period_s;
  frame_.unit_count = config_.unit_count;
  source_(device_time_s, stats_.streaming && !paused_,
          &frame_);  // every period, so a simulation behind it keeps real time

  if (master_fd_ < 0) {  // vanished
    CheckWatchdog(now_ns);
    return;
  }

  pollfd fd{master_fd_, POLLIN, 0};
  ::poll(&fd, 1, 0);
  const bool host_present = (fd.revents & POLLHUP) == 0;
  if (host_present && !stats_.host_connected) {
    stats_.host_connected = true;
    ++stats_.connects;
    hello_sent_this_connection_ = false;
    hellos_this_connection_ = 0;
    answers_this_connection_ = 0;
    selected_version_ = 1;  // every connection begins in version 1 until the host chooses
    hello_due_ns_ = now_ns + SecondsToNs(config_.connect_delay_s);
    decoder_.Reset();
  }
  // Read before acting on a hangup: a host's last words (stream stop, motor off) come just before it.
  if (fd.revents & POLLIN) {
    std::array<uint8_t, 4096> in;
    for (;;) {
      const ssize_t n = ::read(master_fd_, in.data(), in.size());
      if (n <= 0) break;
      std::span<const uint8_t> rest(in.data(), static_cast<size_t>(n));
      while (!rest.empty()) {
        const FeedResult fed = decoder_.Feed(rest, &packet_);
        rest = rest.subspan(fed.consumed);
        if (fed.packet) HandleHostPacket(packet_, now_ns);
      }
    }
    stats_.host_corrupt = decoder_.stats().corrupt();
  }
  // After reading: a command that waited in the pty while this thread was descheduled still counts.
  CheckWatchdog(now_ns);
  if (!host_present) {
    if (stats_.host_connected) {
      // The host closed the port: a real device would see the USB session end.
      stats_.host_connected = false;
      stats_.streaming = false;
      out_size_ = 0;
      held_size_ = 0;
    }
    return;
  }
  if (now_ns >= hello_due_ns_) {
    QueueHello();
    hello_due_ns_ = now_ns + SecondsToNs(config_.hello_period_s);
  }
  if (stats_.streaming && !paused_) {
    // The hand's sample goes first, so a frame's host-side tap carries the hand of its own period.
    SendHand(device_time_s, static_cast<uint32_t>(device_tick * static_cast<uint64_t>(1e6 * period_s)));
    const uint16_t sequence = frame_seq_++;
    const uint64_t index = frame_index_++;
    if (drop_frames_ > 0) {
      --drop_frames_;
      ++stats_.frames_dropped;
    } else {
      FromRawFrame(frame_, sequence,
                   static_cast<uint32_t>(device_tick * static_cast<uint64_t>(1e6 * period_s)), &wire_frame_);
      if (frame_unit_count_ > 0) wire_frame_.unit_count = static_cast<uint8_t>(frame_unit_count_);
      std::array<uint8_t, kMaxWirePacketSize> out;
      size_t size = EncodePacket(wire_frame_, out);
      const bool corrupt = size > 0 && corrupt_frames_ > 0;
      const bool truncate = size > 0 && truncate_bytes_ > 0 && !corrupt;  // one fault per frame: one refusal
      if (size > 0 && reorder_frames_ > 0 && held_size_ == 0 && !corrupt && !truncate) {
        // Held back; sent after the next reorder_later_ sequence numbers.
        std::copy_n(out.begin(), size, held_.begin());
        held_size_ = size;
        held_index_ = index;
        held_countdown_ = reorder_later_;
        --reorder_frames_;
      } else if (size > 0 && out_size_ + size > out_.size()) {
        ++stats_.frames_overflowed;  // a pending corruption waits for a frame that is sent
      } else if (size > 0) {
        if (corrupt) {
          --corrupt_frames_;
          ++stats_.frames_corrupted;
          uint8_t& byte = out[size / 2];
          byte = (byte ^ 0x5A) != 0 ? static_cast<uint8_t>(byte ^ 0x5A) : static_cast<uint8_t>(byte ^ 0xA5);
        }
        if (truncate) {
          // Remove bytes just before the delimiter: the packet ends early.
          const size_t cut = std::min<size_t>(static_cast<size_t>(truncate_bytes_), size - 2);
          out[size - 1 - cut] = 0x00;
          size -= cut;
          truncate_bytes_ = 0;
          ++stats_.frames_corrupted;
        }
        SendFrame(std::span<const uint8_t>(out.data(), size), index, !corrupt && !truncate);
      }
      stats_.last_frame_sequence = sequence;
    }
    if (held_size_ > 0 && index != held_index_ && --held_countdown_ <= 0) ReleaseHeld();
  }
  Flush();
}

void DeviceEmulator::Run() {
  const int64_t period_ns = SecondsToNs(1.0 / config_.frame_rate_hz);
  int64_t next_ns = NowNs();
  while (running_.load()) {
    next_ns += period_ns;
    const int64_t now_ns = NowNs();
    if (next_ns > now_ns) {
      std::this_thread::sleep_for(std::chrono::nanoseconds(next_ns - now_ns));
    } else if (now_ns - next_ns > 50 * period_ns) {
      next_ns = now_ns;  // far behind (machine busy): skip, do not burst
    }
    std::lock_guard lock(mutex_);
    Tick(NowNs());
  }
}

void DeviceEmulator::CorruptFrames(int count) {
  std::lock_guard lock(mutex_);
  corrupt_frames_ += count;
}

void DeviceEmulator::CorruptHand(int count) {
  std::lock_guard lock(mutex_);
  corrupt_hand_ += count;
}

void DeviceEmulator::DropHand(int count) {
  std::lock_guard lock(mutex_);
  drop_hand_ += count;
}

void DeviceEmulator::InjectMalformedHand(int count) {
  std::lock_guard lock(mutex_);
  malformed_hand_ += count;
}

void DeviceEmulator::ReorderFrames(int count, int later) {
  if (later < 1)
    throw std::invalid_argument("emulator: ReorderFrames later = " + std::to_string(later) +
                                ": must be >= 1");
  std::lock_guard lock(mutex_);
  reorder_frames_ += count;
  reorder_later_ = later;
}

void DeviceEmulator::DropFrames(int count) {
  std::lock_guard lock(mutex_);
  drop_frames_ += count;
}

void DeviceEmulator::InjectGarbage(int bytes, bool delimited) {
  std::lock_guard lock(mutex_);
  std::vector<uint8_t> garbage;
  garbage.reserve(static_cast<size_t>(bytes) + 1);
  for (int i = 0; i < bytes; ++i) {
    rng_ = rng_ * 1664525u + 1013904223u;  // fixed LCG: reproducible garbage
    garbage.push_back(static_cast<uint8_t>(1 + (rng_ >> 24) % 255));
  }
  if (delimited) garbage.push_back(0);
  // All or nothing: a part of it would merge with the next packet and change what the host counts.
  if (Queue(garbage) && delimited && bytes > 0) ++stats_.garbage_packets;
}

void DeviceEmulator::InjectOversize(int bytes) {
  std::lock_guard lock(mutex_);
  const uint8_t filler = 0x42;
  for (int i = 0; i < bytes; ++i) Queue(std::span<const uint8_t>(&filler, 1));
  const uint8_t zero = 0;
  Queue(std::span<const uint8_t>(&zero, 1));
}

void DeviceEmulator::InjectUnknownType(uint8_t type) {
  std::lock_guard lock(mutex_);
  const uint8_t body[] = {type, kProtocolVersion, 0, 0, 0xAB, 0xCD};
  std::array<uint8_t, kMaxWirePacketSize> out;
  Queue(std::span<const uint8_t>(out.data(), EncodeBody(body, out)));
}

void DeviceEmulator::InjectBadVersion(uint8_t version) {
  std::lock_guard lock(mutex_);
  std::array<uint8_t, kHelloBodySize> body{};
  body[0] = static_cast<uint8_t>(PacketType::kHello);
  body[1] = version;
  body[6] = static_cast<uint8_t>(config_.unit_count);
  std::array<uint8_t, kMaxWirePacketSize> out;
  Queue(std::span<const uint8_t>(out.data(), EncodeBody(body, out)));
}

void DeviceEmulator::TruncateNextFrame(int bytes) {
  std::lock_guard lock(mutex_);
  truncate_bytes_ = bytes;
}

void DeviceEmulator::PauseFrames(bool paused) {
  std::lock_guard lock(mutex_);
  paused_ = paused;
}

void DeviceEmulator::SetFrameUnitCount(int unit_count) {
  std::lock_guard lock(mutex_);
  frame_unit_count_ = unit_count;
}

bool DeviceEmulator::Settle(double timeout_s) {
  {
    std::lock_guard lock(mutex_);
    ++stats_.settles;
    paused_ = true;
    if (master_fd_ < 0 || !stats_.host_connected) {
      ++stats_.settles_unconfirmed;
      return false;
    }
    ReleaseHeld();
    QueueHello();  // behind everything queued: its answer means all of it was read
    hello_due_ns_ = NowNs() + SecondsToNs(config_.hello_period_s);
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    {
      std::lock_guard lock(mutex_);
      if (master_fd_ >= 0 && stats_.host_connected && out_size_ == 0 &&
          answers_this_connection_ >= hellos_this_connection_)
        return true;
      if (master_fd_ < 0 || !stats_.host_connected || std::chrono::steady_clock::now() >= deadline) {
        ++stats_.settles_unconfirmed;
        return false;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

void DeviceEmulator::Vanish() {
  std::lock_guard lock(mutex_);
  if (master_fd_ >= 0) ++stats_.vanishes;
  ClosePty();
}

void DeviceEmulator::Return() {
  std::lock_guard lock(mutex_);
  if (master_fd_ < 0) OpenPty();
}

void DeviceEmulator::Reboot() {
  std::lock_guard lock(mutex_);
  frame_seq_ = 0;
  frame_index_ = 0;
  newest_intact_valid_ = false;
  held_size_ = 0;  // the old session's held-back frame is never sent
  hello_seq_ = 0;
  hand_seq_ = 0;
  selected_version_ = 1;  // a restarted device speaks version 1 until the host chooses again
  time_base_tick_ = tick_;
  stats_.streaming = false;
  SetMotor({});
  hello_due_ns_ = NowNs();  // a booting device says HELLO at once
}

EmulatorStats DeviceEmulator::stats() const {
  std::lock_guard lock(mutex_);
  EmulatorStats stats = stats_;
  stats.frames_trailing = frame_index_ - (newest_intact_valid_ ? newest_intact_index_ + 1 : 0);
  return stats;
}

EmulatedMotor DeviceEmulator::motor() const {
  std::lock_guard lock(mutex_);
  return motor_;
}

std::string DeviceEmulator::slave_path() const {
  std::lock_guard lock(mutex_);
  return slave_path_;
}

}  // namespace graspbed::hardware
