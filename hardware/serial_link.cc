#include "hardware/serial_link.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

namespace graspbed::hardware {
namespace {

constexpr uint32_t kPendingBit = 1u << 31;
/// In the pending word's low half: the high half carries the answered frame's decode time.
constexpr uint32_t kHasArrivalBit = 1u << 30;

/// A pending command and, when it answers a frame, when that frame was decoded, in one word so the
/// I/O thread takes both together [microseconds, modulo 2^32: differences stay right for 71 min].
uint64_t WithArrival(uint32_t command, int64_t arrival_ns) {
  if (arrival_ns == 0) return command;
  return (static_cast<uint64_t>(static_cast<uint32_t>(arrival_ns / 1000)) << 32) | command | kHasArrivalBit;
}

int Milliseconds(double seconds) { return std::max(1, static_cast<int>(std::lround(seconds * 1e3))); }

uint32_t PackMotor(const hand::HandCommand& command) {
  uint8_t flags = 0;
  if (command.enable) flags |= kMotorEnable;
  if (command.brake) flags |= kMotorBrake;
  const int16_t effort = command.enable ? EffortToWire(command.grip_effort) : 0;
  return kPendingBit | (static_cast<uint32_t>(static_cast<uint16_t>(effort)) << 8) | flags;
}

}  // namespace

FrameOrder ClassifyFrameOrder(int sequence_step, int64_t time_step_us, int64_t period_us) {
  if (sequence_step < 0 && sequence_step >= -kLateFrameWindow && time_step_us < 0 &&
      -time_step_us <= kLateFrameWindow * period_us) {
    return FrameOrder::kLate;
  }
  if (sequence_step <= 0 || time_step_us <= 0) return FrameOrder::kRestart;
  return sequence_step == 1 ? FrameOrder::kNext : FrameOrder::kGap;
}

SerialLink::SerialLink(std::string path, const HardwareConfig& config, LinkRole role, int expected_units,
                       std::string layout_name)
    : path_(std::move(path)),
      config_(config),
      role_(role),
      expected_units_(expected_units),
      layout_name_(std::move(layout_name)) {
  config_.Validate();
  if (path_.empty()) throw std::invalid_argument("serial link: no port given");
  if (has_sensor() && (expected_units_ < 1 || expected_units_ > kMaxUnitsOnWire)) {
    throw std::invalid_argument("serial link: layout '" + layout_name_ + "' has " +
                                std::to_string(expected_units_) + " units; a 512-byte packet carries 1..62");
  }
  wake_fd_ = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (wake_fd_ < 0) throw std::runtime_error("serial link: eventfd failed");
}

SerialLink::~SerialLink() {
  Stop();
  if (wake_fd_ >= 0) ::close(wake_fd_);
}

int64_t SerialLink::NowNs() const {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

void SerialLink::Wake() {
  const uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = ::write(wake_fd_, &one, sizeof(one));
}

void SerialLink::Start() {
  if (started_) return;
  port_.Open(path_, config_.baud);  // PortError goes to the caller as is
  decoder_.Reset();
  stop_ = false;
  refused_ = false;
  last_frame_ns_ = NowNs();
  thread_ = std::thread([this] { Run(); });
  started_ = true;

  std::unique_lock lock(info_mutex_);
  const bool answered = info_cv_.wait_for(lock, std::chrono::duration<double>(config_.hello_timeout_s),
                                          [&] { return connected_.load() || refused_.load(); });
  if (connected_.load()) return;
  const std::string error = refused_.load() ? error_ : std::string();
  lock.unlock();
  Stop();
  if (!answered || error.empty()) {
    std::ostringstream message;
    message << "serial port " << path_ << ": no HELLO from the device within " << config_.hello_timeout_s
            << " s: is it a graspbed readout (protocol v1 or v2) at the configured baud (" << config_.baud
            << ")?";
    throw std::runtime_error(message.str());
  }
  throw std::runtime_error(error);
}

void SerialLink::Stop() {
  if (!started_) return;
  stop_ = true;
  Wake();
  if (thread_.joinable()) thread_.join();
  started_ = false;
}

void SerialLink::SetError(const std::string& message) {
  std::lock_guard lock(info_mutex_);
  error_ = message;
}

std::string SerialLink::last_error() const {
  std::lock_guard lock(info_mutex_);
  return error_;
}

HelloPacket SerialLink::hello() const {
  std::lock_guard lock(info_mutex_);
  return hello_;
}

sensor::BackendCounters SerialLink::counters() const {
  sensor::BackendCounters c;
  c.frames = counter_frames_.load();
  c.corrupt = counter_corrupt_.load();
  c.dropped = counter_dropped_.load();
  c.unknown_packets = counter_unknown_.load();
  c.reconnects = counter_reconnects_.load();
  c.stale_periods = counter_stale_.load();
  c.sessions = counter_sessions_.load();
  return c;
}

HandCounters SerialLink::hand_counters() const {
  HandCounters c;
  c.messages = hand_messages_.load();
  c.malformed = decoder_hand_errors_.load();
  c.dropped = hand_dropped_.load();
  c.late = hand_late_.load();
  return c;
}

bool SerialLink::TryTakeHand(hand::HandState* state, uint64_t* last_id, int64_t* arrival_ns) {
  if (hand_published_.load(std::memory_order_acquire) == *last_id) return false;
  std::unique_lock lock(hand_mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return false;
  *state = hand_slot_;
  *last_id = hand_slot_id_;
  *arrival_ns = hand_slot_arrival_ns_;
  return true;
}

double SerialLink::SecondsSinceLastFrame() const {
  return static_cast<double>(NowNs() - last_frame_ns_.load(std::memory_order_acquire)) * 1e-9;
}

bool SerialLink::TryTakeFrame(sensor::RawFrame* frame, uint64_t* last_id, uint64_t* session) {
  if (published_.load(std::memory_order_acquire) == *last_id) return false;
  std::unique_lock lock(frame_mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return false;
  *frame = slot_;
  *last_id = slot_id_;
  if (session != nullptr) *session = slot_session_;
  taken_arrival_ns_.store(slot_arrival_ns_, std::memory_order_release);
  return true;
}

bool SerialLink::WaitForFrame(uint64_t last_id, double timeout_s) {
  std::unique_lock lock(wait_mutex_);
  return frame_cv_.wait_for(lock, std::chrono::duration<double>(timeout_s),
                            [&] { return published_.load(std::memory_order_acquire) != last_id; });
}

void SerialLink::EnableTap(size_t capacity) {
  std::lock_guard lock(tap_mutex_);
  tap_.assign(capacity, TappedFrame{});
  tap_head_ = tap_size_ = 0;
}

bool SerialLink::PopTap(TappedFrame* out) {
  std::lock_guard lock(tap_mutex_);
  if (tap_size_ == 0) return false;
  *out = tap_[tap_head_];
  tap_head_ = (tap_head_ + 1) % tap_.size();
  --tap_size_;
  return true;
}

hand::WriteStatus SerialLink::SendMotor(const hand::HandCommand& command, int64_t frame_arrival_ns) {
  if (!connected_.load(std::memory_order_acquire)) return hand::WriteStatus::kDisconnected;
  pending_motor_.store(WithArrival(PackMotor(command), frame_arrival_ns), std::memory_order_release);
  Wake();
  return hand::WriteStatus::kOk;
}

void SerialLink::MotorOff(double timeout_s) {
  if (!started_ || !connected_.load()) return;
  const uint64_t before = motor_sent_.load();
  pending_motor_.store(PackMotor({.grip_effort = 0.0, .enable = false, .brake = false}));
  Wake();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (motor_sent_.load() == before && connected_.load() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
}

bool SerialLink::WritePacket(std::span<const uint8_t> bytes) {
  const IoResult result = port_.Write(bytes, Milliseconds(config_.write_timeout_s));
  if (result.status == IoStatus::kHangup || result.status == IoStatus::kError) {
    OnLost();
    return false;
  }
  // A timeout leaves a partial packet on the wire; the device resyncs at our next delimiter.
  return result.status == IoStatus::kOk;
}

void SerialLink::SendStream(bool start) {
  std::array<uint8_t, kMaxWirePacketSize> out;
  const size_t size = EncodePacket(StreamControlPacket{.sequence = stream_seq_++, .start = start}, out);
  WritePacket(std::span<const uint8_t>(out.data(), size));
}

void SerialLink::SendSelect(uint8_t version) {
  std::array<uint8_t, kMaxWirePacketSize> out;
  const size_t size = EncodePacket(ProtocolSelectPacket{.sequence = select_seq_++, .version = version}, out);
  WritePacket(std::span<const uint8_t>(out.data(), size));
}

void SerialLink::SendPendingMotor() {
  const uint64_t word = pending_motor_.exchange(0, std::memory_order_acq_rel);
  const uint32_t pending = static_cast<uint32_t>(word);
  if (!(pending & kPendingBit) || !handshake_ || !port_.is_open()) return;  // never before HELLO
  MotorCommandPacket packet;
  packet.sequence = motor_seq_++;
  packet.effort = static_cast<int16_t>(static_cast<uint16_t>(pending >> 8));
  packet.flags = static_cast<uint8_t>(pending & 0xFFu);
  std::array<uint8_t, kMaxWirePacketSize> out;
  const size_t size = EncodePacket(packet, out);
  if (!WritePacket(std::span<const uint8_t>(out.data(), size))) return;
  motor_sent_.fetch_add(1);
  // The first command written after a frame was taken answers it; later ones (the loop ticking again
  // on the same frame) do not count again.
  const uint32_t arrival_us = static_cast<uint32_t>(word >> 32);
  if (latency_.enabled() && (pending & kHasArrivalBit) &&
      (!answered_any_ || arrival_us != last_answered_arrival_us_)) {
    const uint32_t now_us = static_cast<uint32_t>(NowNs() / 1000);
    latency_.Record(static_cast<int64_t>(static_cast<uint32_t>(now_us - arrival_us)) * 1000);
    last_answered_arrival_us_ = arrival_us;
    answered_any_ = true;
  }
}

void SerialLink::NewSession() {
  counter_sessions_.fetch_add(1, std::memory_order_acq_rel);
  have_last_frame_ = false;
  have_last_hello_ = false;
  have_last_hand_ = false;
}

void SerialLink::HandleHello(const HelloPacket& hello) {
  // HELLO numbers only go forward within a session; backwards (or the same) means a reboot.
  const bool rebooted = have_last_hello_ && static_cast<int16_t>(hello.sequence - last_hello_seq_) <= 0;
  if (has_sensor() && hello.unit_count != expected_units_) {
    std::ostringstream message;
    message << "serial port " << path_ << ": the device reports " << static_cast<int>(hello.unit_count)
            << " units in its HELLO but layout '" << layout_name_ << "' has " << expected_units_
            << ": refusing to run (give the matching --layout, or connect the right device)";
    {
      // Under the lock Start() waits with, or its wait could miss this notification.
      std::lock_guard lock(info_mutex_);
      error_ = message.str();
      refused_ = true;
      connected_ = false;
    }
    info_cv_.notify_all();
    return;
  }
  {
    std::lock_guard lock(info_mutex_);
    hello_ = hello;
  }
  frame_period_us_ =
      hello.nominal_rate_hz > 0 ? std::max<int64_t>(1, 1'000'000 / hello.nominal_rate_hz) : 1000;
  if (!handshake_) {
    handshake_ = true;
    last_refused_units_ = -1;  // refused frames of the new connection are reported afresh
    if (ever_connected_) counter_reconnects_.fetch_add(1);
    if (!ever_connected_) {
      counter_sessions_.fetch_add(1);
    } else if (rebooted) {
      // The device restarted while it was away (a USB reset usually reboots it): its HELLO numbers
      // began again. Frames may not tell (sequence and device time can look like a forward jump).
      NewSession();
    }
    ever_connected_ = true;
    refused_ = false;
    last_frame_ns_ = NowNs();  // the stale clock starts with the handshake
    connected_.store(true, std::memory_order_release);
    { std::lock_guard lock(info_mutex_); }
    info_cv_.notify_all();
  } else if (rebooted) {
    NewSession();
  }
  have_last_hello_ = true;
  last_hello_seq_ = hello.sequence;
  // The version for this connection: the lower of the device's and ours. Chosen again at every
  // HELLO (a device that rebooted forgot it), before the stream starts, so no frame goes without it.
  const uint8_t version = std::min(kProtocolVersion, DeviceVersion(hello));
  protocol_version_.store(version, std::memory_order_release);
  if (has_sensor() && version >= kHandProtocolVersion) SendSelect(version);
  // Answering every HELLO with start is idempotent and restarts a device that rebooted.
  if (has_sensor()) SendStream(true);
}

void SerialLink::HandleFrame(const TactileFramePacket& frame) {
  if (!has_sensor() || !handshake_) return;  // frames before the HELLO belong to nobody's session
  const int64_t arrival_ns = NowNs();  // the frame's last byte was just read
  if (frame.unit_count != expected_units_) {
    ++extra_corrupt_;
    // The message once per episode of refused frames (or change of count within one), not per
    // frame: this path runs at the frame rate. An accepted frame or a handshake ends the episode.
    if (frame.unit_count == last_refused_units_) return;
    last_refused_units_ = frame.unit_count;
    std::ostringstream message;
    message << "serial port " << path_ << ": frames carry " << static_cast<int>(frame.unit_count)
            << " units but layout '" << layout_name_ << "' has " << expected_units_
            << "; frames dropped from device time " << std::fixed << std::setprecision(3)
            << frame.device_time_us * 1e-6 << " s";
    SetError(message.str());
    return;
  }
  last_refused_units_ = -1;  // a later refused frame starts a new episode and is reported again
  if (have_last_frame_) {
    const int seq_step = static_cast<int16_t>(frame.sequence - last_frame_seq_);
    const int64_t time_step = static_cast<int32_t>(frame.device_time_us - last_frame_time_us_);
    switch (ClassifyFrameOrder(seq_step, time_step, frame_period_us_)) {
      case FrameOrder::kLate:
        // Older than a frame already published: never handed to the loop (nor to the log), and its
        // sequence number stays counted in dropped, where the newer frame's gap put it.
        counter_reordered_.fetch_add(1, std::memory_order_acq_rel);
        return;
      case FrameOrder::kRestart:
        NewSession();  // duplicate or backwards sequence / device time: the device restarted
        break;
      case FrameOrder::kGap:
        counter_dropped_.fetch_add(static_cast<uint64_t>(seq_step - 1));
        break;
      case FrameOrder::kNext:
        break;
    }
  }
  have_last_frame_ = true;
  last_frame_seq_ = frame.sequence;
  last_frame_time_us_ = frame.device_time_us;

  ToRawFrame(frame, &scratch_);
  const uint64_t session = counter_sessions_.load();
  {
    std::lock_guard lock(frame_mutex_);
    slot_ = scratch_;
    slot_session_ = session;
    slot_arrival_ns_ = arrival_ns;
    slot_id_ = published_.load() + 1;
    published_.store(slot_id_, std::memory_order_release);
  }
  last_frame_ns_.store(NowNs(), std::memory_order_release);
  counter_frames_.fetch_add(1);
  stale_ = false;
  { std::lock_guard lock(wait_mutex_); }
  frame_cv_.notify_all();
  if (!tap_.empty()) Tap(session);
}

void SerialLink::Tap(uint64_t session) {
  std::lock_guard lock(tap_mutex_);
  if (tap_size_ == tap_.size()) {
    tap_overflows_.fetch_add(1);
    return;
  }
  TappedFrame& entry = tap_[(tap_head_ + tap_size_) % tap_.size()];
  entry.frame = scratch_;
  entry.session = session;
  entry.hand = hand_scratch_;
  ++tap_size_;
}

void SerialLink::HandleHand(const HandPacket& hand) {
  if (!has_sensor() || !handshake_) return;  // before the HELLO: nobody's session
  const int64_t arrival_ns = NowNs();
  if (have_last_hand_) {
    const int step = static_cast<int16_t>(hand.sequence - last_hand_seq_);
    if (step <= 0 && step >= -kLateFrameWindow) {
      hand_late_.fetch_add(1, std::memory_order_acq_rel);  // older than what the loop may hold
      return;
    }
    if (step > 1) hand_dropped_.fetch_add(static_cast<uint64_t>(step - 1));
  }
  have_last_hand_ = true;
  last_hand_seq_ = hand.sequence;
  ToHandState(hand, &hand_scratch_);
  hand_scratch_.time_s = static_cast<double>(hand.device_time_us) * 1e-6;
  hand_scratch_.stale = false;
  {
    std::lock_guard lock(hand_mutex_);
    hand_slot_ = hand_scratch_;
    hand_slot_arrival_ns_ = arrival_ns;
    hand_slot_id_ = hand_published_.load() + 1;
    hand_published_.store(hand_slot_id_, std::memory_order_release);
  }
  hand_messages_.fetch_add(1);
}

void SerialLink::HandlePacket(const DecodedPacket& packet) {
  switch (packet.type) {
    case PacketType::kHello:
      HandleHello(packet.hello);
      break;
    case PacketType::kTactileFrame:
      HandleFrame(packet.frame);
      break;
    case PacketType::kHand:
      HandleHand(packet.hand);
      break;
    case PacketType::kMotorCommand:
    case PacketType::kStreamControl:
    case PacketType::kProtocolSelect:
      ++extra_unknown_;
      break;  // host-to-device types: not for us
  }
}

void SerialLink::OnLost() {
  port_.Close();
  connected_.store(false, std::memory_order_release);
  handshake_ = false;
  protocol_version_.store(0, std::memory_order_release);  // chosen again with the next HELLO
  hand_scratch_ = hand::HandState{};  // a frame of the next connection carries no hand of this one
  pending_motor_.store(0);  // commands for the old connection must not reach the new one
}

void SerialLink::CheckStale() {
  // From the first handshake on: a device that says HELLO but never streams is stale too.
  if (!ever_connected_ || stale_) return;
  if (SecondsSinceLastFrame() > config_.stale_timeout_s) {
    stale_ = true;
    counter_stale_.fetch_add(1);
  }
}

void SerialLink::Run() {
  std::array<uint8_t, 4096> buffer;
  double backoff_s = config_.reconnect_backoff_s;
  const int poll_ms = Milliseconds(config_.poll_interval_s);
  while (!stop_.load()) {
    if (!port_.is_open()) {
      CheckStale();
      pollfd wake{wake_fd_, POLLIN, 0};
      if (::poll(&wake, 1, Milliseconds(backoff_s)) > 0) {
        uint64_t value;
        [[maybe_unused]] const ssize_t n = ::read(wake_fd_, &value, sizeof(value));
      }
      if (stop_.load()) break;
      try {
        port_.Open(path_, config_.baud);
      } catch (const PortError&) {
        backoff_s = std::min(2.0 * backoff_s, config_.reconnect_backoff_max_s);
        continue;
      }
      backoff_s = config_.reconnect_backoff_s;
      decoder_.Reset();
      handshake_ = false;  // wait for HELLO again
      continue;
    }
    const IoResult result = port_.Read(buffer, poll_ms, wake_fd_);
    if (result.status == IoStatus::kHangup || result.status == IoStatus::kError) {
      OnLost();
      continue;
    }
    std::span<const uint8_t> rest(buffer.data(), result.bytes);
    while (!rest.empty()) {
      const FeedResult fed = decoder_.Feed(rest, &packet_);
      rest = rest.subspan(fed.consumed);
      if (fed.packet) HandlePacket(packet_);
      if (!port_.is_open()) break;  // a write inside failed: the device is gone
    }
    counter_corrupt_.store(decoder_.stats().corrupt() + extra_corrupt_);
    counter_unknown_.store(decoder_.stats().unknown() + extra_unknown_);
    decoder_hand_errors_.store(decoder_.stats().hand_errors);
    if (port_.is_open()) SendPendingMotor();
    CheckStale();
  }
  Shutdown();
}

void SerialLink::Shutdown() {
  if (port_.is_open() && handshake_) {
    if (has_sensor()) SendStream(false);
    if (has_motor() && port_.is_open()) {
      MotorCommandPacket off{.sequence = motor_seq_++, .effort = 0, .flags = 0};
      std::array<uint8_t, kMaxWirePacketSize> out;
      const size_t size = EncodePacket(off, out);
      if (WritePacket(std::span<const uint8_t>(out.data(), size))) motor_sent_.fetch_add(1);
    }
    port_.Drain(50);
  }
  port_.Close();
  connected_.store(false);
  handshake_ = false;
}

}  // namespace graspbed::hardware
