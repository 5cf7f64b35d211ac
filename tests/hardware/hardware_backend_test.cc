// HardwareBackend / HardwareActuator against the DeviceEmulator over real pseudo-terminals: the
// handshake, every fault of docs/protocol.md "What the host must survive" with exact counters, the
// watchdog, and clean shutdown.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>

#include "sensor/readout.h"
#include "hardware/device_emulator.h"
#include "hardware/hardware_backend.h"
#include "hardware/stream_decoder.h"
#include "tests/hardware/serial_test_util.h"

namespace graspbed::hardware {
namespace {

using test_support::WaitFor;

constexpr int kUnits = 20;
constexpr double kResistanceTolOhm = 1e-3;  // wire resolution is 1 mOhm

// A device written packet by packet, for cases the DeviceEmulator cannot stage (any sequence number
// or device time). A pty whose slave is exposed at `link`, like the emulator's.
class ScriptedDevice {
 public:
  explicit ScriptedDevice(std::string link) : link_(std::move(link)) {}
  ~ScriptedDevice() { Vanish(); }
  ScriptedDevice(const ScriptedDevice&) = delete;
  ScriptedDevice& operator=(const ScriptedDevice&) = delete;

  /// A new pty behind the link (the device is plugged in).
  void Appear() {
    int slave = -1;
    char name[256] = {};
    ASSERT_EQ(openpty(&master_, &slave, name, nullptr, nullptr), 0);
    termios raw{};
    tcgetattr(slave, &raw);
    cfmakeraw(&raw);
    tcsetattr(slave, TCSANOW, &raw);
    ::close(slave);
    fcntl(master_, F_SETFL, fcntl(master_, F_GETFL) | O_NONBLOCK);
    ::unlink(link_.c_str());
    ASSERT_EQ(symlink(name, link_.c_str()), 0);
  }
  /// The pty closes and the link goes (unplugged).
  void Vanish() {
    if (master_ < 0) return;
    ::close(master_);
    master_ = -1;
    ::unlink(link_.c_str());
  }
  /// Sends HELLOs numbered from `hello_seq` (a device repeats them; the host may flush the first
  /// while opening the port) until the host answers with STREAM_CONTROL start.
  bool Handshake(uint16_t hello_seq, int units) {
    return test_support::WaitFor(
        [&] {
          HelloPacket hello{.sequence = hello_seq++,
                            .firmware_version = 1,
                            .unit_count = static_cast<uint8_t>(units),
                            .nominal_rate_hz = 1000,
                            .nominal_r0_milliohm = 3'400'000};
          Send(hello);
          return test_support::WaitFor([&] { return ReadStreamStart(); }, 0.05);
        },
        test_support::kWaitTimeoutS);
  }
  void Send(const auto& packet) {
    std::array<uint8_t, kMaxWirePacketSize> out;
    const size_t size = EncodePacket(packet, out);
    ASSERT_GT(size, 0u);
    size_t written = 0;
    while (written < size) {
      const ssize_t n = ::write(master_, out.data() + written, size - written);
      if (n > 0) {
        written += static_cast<size_t>(n);
      } else {
        pollfd fd{master_, POLLOUT, 0};
        ::poll(&fd, 1, 10);
      }
    }
  }
  void SendFrames(uint16_t first_seq, uint32_t first_time_us, int count, int units) {
    TactileFramePacket frame;
    frame.unit_count = static_cast<uint8_t>(units);
    for (int k = 0; k < units; ++k) frame.r1_milliohm[k] = frame.r2_milliohm[k] = 3'400'000;
    for (int i = 0; i < count; ++i) {
      frame.sequence = static_cast<uint16_t>(first_seq + i);
      frame.device_time_us = first_time_us + 1000u * static_cast<uint32_t>(i);
      Send(frame);
    }
  }

 private:
  bool ReadStreamStart() {
    std::array<uint8_t, 256> in;
    const ssize_t n = ::read(master_, in.data(), in.size());
    if (n <= 0) return false;
    std::span<const uint8_t> rest(in.data(), static_cast<size_t>(n));
    bool started = false;
    while (!rest.empty()) {
      const FeedResult fed = decoder_.Feed(rest, &packet_);
      rest = rest.subspan(fed.consumed);
      if (fed.packet && packet_.type == PacketType::kStreamControl && packet_.stream.start) started = true;
    }
    return started;
  }

  std::string link_;
  int master_ = -1;
  StreamDecoder decoder_;
  DecodedPacket packet_;
};

class HardwareTest : public ::testing::Test {
 protected:
  void StartEmulator(int units = kUnits, double connect_delay_s = 0.02) {
    EmulatorConfig config;
    config.link_path = test_support::UniqueLinkPath("hw");
    config.unit_count = units;
    config.connect_delay_s = connect_delay_s;
    emulator_ = std::make_unique<DeviceEmulator>(config, test_support::TestFrameSource);
    emulator_->Start();
    hw_config_.port = config.link_path;
  }

  void StartHost() {
    backend_ = std::make_unique<HardwareBackend>(hw_config_, kUnits, "test_20");
    actuator_ = std::make_unique<HardwareActuator>(*backend_, hw_config_);
    backend_->Start();
    actuator_->Start();
  }

  // Waits until the host has taken in every frame the emulator sent, minus `lost` ones.
  bool WaitHostCaughtUp(uint64_t frames_before_host, uint64_t sent_before, uint64_t lost) {
    return WaitFor([&] {
      const uint64_t sent = emulator_->stats().frames_sent - sent_before;
      return backend_->counters().frames - frames_before_host + lost == sent;
    });
  }

  // A baseline with nothing in flight: pauses the stream and waits until the host holds the last
  // frame sent (left in `frame`). Returns false when it never does. The stream stays paused.
  bool PauseAndWaitHostHoldsLastFrame(EmulatorStats* emulator_stats, sensor::RawFrame* frame) {
    emulator_->PauseFrames(true);
    *emulator_stats = emulator_->stats();
    return WaitFor([&] {
      backend_->Read(frame);
      return frame->sequence == emulator_stats->last_frame_sequence;
    });
  }

  void TearDown() override {
    actuator_.reset();
    backend_.reset();
    emulator_.reset();
  }

  HardwareConfig hw_config_;
  std::unique_ptr<DeviceEmulator> emulator_;
  std::unique_ptr<HardwareBackend> backend_;
  std::unique_ptr<HardwareActuator> actuator_;
};

TEST_F(HardwareTest, HandshakeThenFramesArriveIntact) {
  StartEmulator();
  StartHost();
  EXPECT_EQ(backend_->session(), 1u);
  EXPECT_DOUBLE_EQ(backend_->nominal_r0_ohm(), 3400.0);
  EXPECT_EQ(backend_->link()->hello().unit_count, kUnits);
  sensor::RawFrame frame;
  ASSERT_TRUE(WaitFor([&] { return backend_->Read(&frame) == sensor::ReadStatus::kOk; }));
  EXPECT_EQ(frame.unit_count, kUnits);
  for (int k = 0; k < kUnits; ++k) {
    EXPECT_NEAR(frame.r1_ohm[k], 3400.0 + k + frame.time_s, kResistanceTolOhm) << k;
    EXPECT_NEAR(frame.r2_ohm[k], 3400.0 - k, kResistanceTolOhm) << k;
  }
  const auto stats = emulator_->stats();
  EXPECT_GE(stats.stream_starts, 1u);
  EXPECT_EQ(stats.commands_before_hello, 0u);
  const auto counters = backend_->counters();
  EXPECT_EQ(counters.corrupt, 0u);
  EXPECT_EQ(counters.dropped, 0u);
  EXPECT_EQ(counters.reconnects, 0u);
}

TEST_F(HardwareTest, UnitCountMismatchIsRefusedClearly) {
  StartEmulator(/*units=*/9);
  backend_ = std::make_unique<HardwareBackend>(hw_config_, kUnits, "test_20");
  try {
    backend_->Start();
    FAIL() << "a 9-unit device was accepted for a 20-unit layout";
  } catch (const std::runtime_error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("reports 9 units"), std::string::npos) << message;
    EXPECT_NE(message.find("layout 'test_20' has 20"), std::string::npos) << message;
    EXPECT_NE(message.find(hw_config_.port), std::string::npos) << message;
  }
  EXPECT_EQ(emulator_->stats().stream_starts, 0u);  // refused before asking for frames
}

TEST_F(HardwareTest, NoHelloMeansATimeoutErrorNotAHang) {
  StartEmulator(kUnits, /*connect_delay_s=*/30.0);
  hw_config_.hello_timeout_s = 0.3;
  backend_ = std::make_unique<HardwareBackend>(hw_config_, kUnits, "test_20");
  try {
    backend_->Start();
    FAIL() << "started without a HELLO";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("no HELLO"), std::string::npos) << error.what();
  }
}

TEST_F(HardwareTest, NoCommandBeforeHello) {
  constexpr double kConnectDelayS = 0.3;
  // Clocked from before the emulator starts, so a write within the delay is one before it connected.
  const auto begin = std::chrono::steady_clock::now();
  StartEmulator(kUnits, kConnectDelayS);
  backend_ = std::make_unique<HardwareBackend>(hw_config_, kUnits, "test_20");
  actuator_ = std::make_unique<HardwareActuator>(*backend_, hw_config_);
  EXPECT_EQ(actuator_->Write({.grip_effort = 0.5}), hand::WriteStatus::kDisconnected);
  std::atomic<bool> started{false};
  std::thread starter([&] {
    backend_->Start();
    started = true;
  });
  // Hammer the actuator during the handshake: nothing may reach the device before its HELLO.
  int writes_before_connect = 0;
  int accepted_before_connect = 0;
  int refused = 0;
  while (!started) {
    const hand::WriteStatus status = actuator_->Write({.grip_effort = 0.5});
    const double since_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
    if (status == hand::WriteStatus::kDisconnected) ++refused;
    // The device is not there before its connect delay: every write in that time is refused,
    // however many the machine's pace allows (about 400 on an idle machine).
    if (since_s < kConnectDelayS) {
      ++writes_before_connect;
      if (status != hand::WriteStatus::kDisconnected) ++accepted_before_connect;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  starter.join();
  std::printf("[ measure ] %d writes before the device connected, %d refused in all\n", writes_before_connect,
              refused);
  EXPECT_GE(writes_before_connect, 1);
  EXPECT_EQ(accepted_before_connect, 0);
  ASSERT_TRUE(WaitFor([&] {
    actuator_->Write({.grip_effort = 0.5});
    return emulator_->stats().motor_commands > 0;
  }));
  EXPECT_EQ(emulator_->stats().commands_before_hello, 0u);
  EXPECT_NEAR(emulator_->motor().effort, 0.5, 1.0 / 32767);
  EXPECT_TRUE(emulator_->motor().enable);
}

TEST_F(HardwareTest, MotorWatchdogStopsTheMotorWhenCommandsStop) {
  StartEmulator();
  StartHost();
  ASSERT_EQ(actuator_->Write({.grip_effort = 0.8}), hand::WriteStatus::kOk);
  ASSERT_TRUE(WaitFor([&] { return emulator_->motor().enable; }));
  // Commands every 10 ms keep it running for 300 ms. A loaded machine can stall a thread beyond the
  // watchdog; the emulator records the longest gap it saw, and the watchdog must agree with it.
  for (int i = 0; i < 30; ++i) {
    actuator_->Write({.grip_effort = 0.8});
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  // One more command so the gap since the loop's last one (this thread may have stalled) is measured.
  const uint64_t before = emulator_->stats().motor_commands;
  actuator_->Write({.grip_effort = 0.8});
  ASSERT_TRUE(WaitFor([&] { return emulator_->stats().motor_commands > before; }));
  const auto fed = emulator_->stats();
  if (fed.max_command_interval_s < 0.1) {
    EXPECT_EQ(fed.watchdog_trips, 0u) << "longest gap " << fed.max_command_interval_s << " s";
  }
  const uint64_t trips_while_fed = fed.watchdog_trips;
  // The last command: the watchdog may not fire earlier than 100 ms after it was written.
  const uint64_t received = emulator_->stats().motor_commands;
  const auto silent_from = std::chrono::steady_clock::now();
  actuator_->Write({.grip_effort = 0.8});
  ASSERT_TRUE(WaitFor([&] { return emulator_->stats().motor_commands > received; }));
  EXPECT_TRUE(emulator_->motor().enable);
  ASSERT_TRUE(WaitFor([&] { return !emulator_->motor().enable; }));
  EXPECT_GE(std::chrono::steady_clock::now() - silent_from, std::chrono::milliseconds(100));
  EXPECT_EQ(emulator_->stats().watchdog_trips, trips_while_fed + 1);
  EXPECT_EQ(emulator_->motor().effort, 0.0);
}

TEST_F(HardwareTest, ScriptedFaultsGiveExactCounters) {
  StartEmulator();
  StartHost();
  ASSERT_TRUE(WaitFor([&] { return backend_->counters().frames > 20; }));
  EmulatorStats emu0;
  sensor::RawFrame frame;
  ASSERT_TRUE(PauseAndWaitHostHoldsLastFrame(&emu0, &frame));
  const auto host0 = backend_->counters();
  emulator_->PauseFrames(false);
  uint64_t lost = 0;  // frames sent but not decodable

  // Each step waits until its effect is on the wire and a good frame followed it.
  auto step = [&](const std::function<void()>& fault, uint64_t corrupt_after, uint64_t frames_lost) {
    fault();
    lost += frames_lost;
    ASSERT_TRUE(WaitFor([&] { return backend_->counters().corrupt - host0.corrupt >= corrupt_after; }));
    const uint64_t frames = backend_->counters().frames;
    ASSERT_TRUE(WaitFor([&] { return backend_->counters().frames > frames + 2; }));
  };
  step([&] { emulator_->CorruptFrames(3); }, 3, 3);          // CRC/COBS errors: corrupt 3, dropped 3
  step([&] { emulator_->DropFrames(4); }, 3, 0);             // never sent: dropped 4
  step([&] { emulator_->InjectGarbage(40, true); }, 4, 0);   // garbage + 0x00: corrupt 1
  step([&] { emulator_->InjectGarbage(40, false); }, 5, 1);  // eats the next frame: corrupt 1, dropped 1
  step([&] { emulator_->InjectOversize(2000); }, 6, 0);      // over 512 bytes: corrupt 1
  step([&] { emulator_->TruncateNextFrame(7); }, 7, 1);      // bytes lost mid-packet: corrupt 1, dropped 1
  step([&] { emulator_->InjectUnknownType(0x33); }, 7, 0);   // unknown 1
  step([&] { emulator_->InjectBadVersion(3); }, 7, 0);       // unknown 1 (rejected version)

  emulator_->PauseFrames(true);
  const auto emu = emulator_->stats();
  ASSERT_TRUE(WaitHostCaughtUp(host0.frames, emu0.frames_sent, lost))
      << "sent " << emu.frames_sent - emu0.frames_sent << " host "
      << backend_->counters().frames - host0.frames;
  const auto host = backend_->counters();
  EXPECT_EQ(host.corrupt - host0.corrupt, 7u);
  // A loaded machine may make the emulator overflow its FIFO (a real device would too): those
  // frames are gaps as well, and counted by both sides.
  const uint64_t overflowed = emu.frames_overflowed - emu0.frames_overflowed;
  EXPECT_EQ(host.dropped - host0.dropped, 3u + 4u + 1u + 1u + overflowed);
  EXPECT_EQ(host.unknown_packets - host0.unknown_packets, 2u);
  EXPECT_EQ(host.sessions, 1u);
  EXPECT_EQ(host.reconnects, 0u);
  EXPECT_EQ(emulator_->stats().frames_dropped - emu0.frames_dropped, 4u);
}

// Frames sent out of order (docs/protocol.md, "Late frames"): a frame older than one already
// published is counted reordered (and its sequence number dropped, as the newer frame's gap), never
// handed to the loop, and neither a huge gap nor a device restart.
TEST_F(HardwareTest, LateFramesAreCountedAndNeverUsed) {
  StartEmulator();
  StartHost();
  ASSERT_TRUE(WaitFor([&] { return backend_->counters().frames > 20; }));
  EmulatorStats emu0;
  sensor::RawFrame frame;
  ASSERT_TRUE(PauseAndWaitHostHoldsLastFrame(&emu0, &frame));
  const auto host0 = backend_->counters();
  const uint64_t reordered0 = backend_->link()->reordered();
  // Every frame the loop reads is newer than the one before.
  uint16_t newest = frame.sequence;
  bool went_back = false;
  auto read = [&] {
    while (backend_->Read(&frame) == sensor::ReadStatus::kOk) {
      if (static_cast<int16_t>(frame.sequence - newest) <= 0) went_back = true;
      newest = frame.sequence;
    }
  };
  emulator_->PauseFrames(false);
  emulator_->ReorderFrames(2, 1);  // two frames each swapped with the next
  ASSERT_TRUE(WaitFor([&] {
    read();
    return backend_->link()->reordered() - reordered0 == 2;
  }));
  emulator_->ReorderFrames(1, 3);  // one frame held back by three
  ASSERT_TRUE(WaitFor([&] {
    read();
    return backend_->link()->reordered() - reordered0 == 3;
  }));
  const uint64_t frames = backend_->counters().frames;
  ASSERT_TRUE(WaitFor([&] {
    read();
    return backend_->counters().frames > frames + 2;
  }));
  emulator_->PauseFrames(true);
  const auto emu = emulator_->stats();
  ASSERT_TRUE(WaitHostCaughtUp(host0.frames, emu0.frames_sent, /*lost=*/3))
      << "the late frames are not frames";
  read();
  EXPECT_FALSE(went_back) << "the loop was given a frame older than one it had";
  const auto host = backend_->counters();
  EXPECT_EQ(emu.frames_reordered - emu0.frames_reordered, 3u);
  EXPECT_EQ(backend_->link()->reordered() - reordered0, 3u);
  // Each late frame's sequence number was missing when the newer one came: a gap of 1 each.
  const uint64_t overflowed = emu.frames_overflowed - emu0.frames_overflowed;
  EXPECT_EQ(host.dropped - host0.dropped, 3u + overflowed);
  EXPECT_EQ(host.sessions, 1u);
  EXPECT_EQ(host.corrupt, host0.corrupt);
}

// Settle: once the host has answered the HELLO sent behind the last frame, nothing is in flight, so a
// disconnect then loses no frame, and the counts on both sides agree exactly.
TEST_F(HardwareTest, ASettledDisconnectLosesNoFrame) {
  hw_config_.reconnect_backoff_s = 0.01;
  hw_config_.reconnect_backoff_max_s = 0.05;
  StartEmulator();
  StartHost();
  ASSERT_TRUE(WaitFor([&] { return backend_->counters().frames > 50; }));
  ASSERT_TRUE(emulator_->Settle(test_support::kWaitTimeoutS));
  const auto settled = emulator_->stats();
  EXPECT_EQ(backend_->counters().frames + backend_->counters().dropped + settled.frames_trailing,
            settled.frames_sent + settled.frames_overflowed);
  emulator_->Vanish();
  ASSERT_TRUE(WaitFor([&] { return !backend_->link()->connected(); }));
  emulator_->Return();
  emulator_->PauseFrames(false);
  ASSERT_TRUE(WaitFor([&] { return backend_->link()->connected(); }));
  const uint64_t frames = backend_->counters().frames;
  ASSERT_TRUE(WaitFor([&] { return backend_->counters().frames > frames + 50; }));
  ASSERT_TRUE(emulator_->Settle(test_support::kWaitTimeoutS));
  const auto emu = emulator_->stats();
  const auto host = backend_->counters();
  EXPECT_EQ(host.frames, emu.frames_sent);
  EXPECT_EQ(host.dropped, emu.frames_overflowed - emu.frames_trailing);
  EXPECT_EQ(host.reconnects, 1u);
  EXPECT_EQ(host.sessions, 1u);
  EXPECT_EQ(emu.vanishes, 1u);
  EXPECT_EQ(emu.settles, 2u);
  EXPECT_EQ(emu.settles_unconfirmed, 0u);
}

TEST_F(HardwareTest, SettleWithoutAHostIsUnconfirmed) {
  StartEmulator();
  EXPECT_FALSE(emulator_->Settle(0.1));
  EXPECT_EQ(emulator_->stats().settles_unconfirmed, 1u);
}

TEST_F(HardwareTest, StaleThenDisconnectedThenRecovers) {
  hw_config_.stale_timeout_s = 0.05;
  hw_config_.disconnect_timeout_s = 0.3;
  StartEmulator();
  StartHost();
  sensor::RawFrame frame;
  ASSERT_TRUE(WaitFor([&] { return backend_->Read(&frame) == sensor::ReadStatus::kOk; }));
  emulator_->PauseFrames(true);
  ASSERT_TRUE(WaitFor([&] { return backend_->Read(&frame) == sensor::ReadStatus::kStale; }));
  EXPECT_TRUE(WaitFor([&] { return backend_->counters().stale_periods == 1u; }));
  ASSERT_TRUE(WaitFor([&] { return backend_->Read(&frame) == sensor::ReadStatus::kDisconnected; }));
  EXPECT_EQ(backend_->counters().stale_periods, 1u);  // one period, however long
  emulator_->PauseFrames(false);
  ASSERT_TRUE(WaitFor([&] { return backend_->Read(&frame) == sensor::ReadStatus::kOk; }));
  emulator_->PauseFrames(true);
  ASSERT_TRUE(WaitFor([&] { return backend_->Read(&frame) == sensor::ReadStatus::kStale; }));
  // The I/O thread counts the period on its own poll cycle, a moment after Read() saw it.
  EXPECT_TRUE(WaitFor([&] { return backend_->counters().stale_periods == 2u; }));
  EXPECT_EQ(backend_->counters().dropped, 0u);  // a pause is not a gap
}

TEST_F(HardwareTest, DeviceVanishesAndReturns) {
  StartEmulator();
  StartHost();
  sensor::RawFrame frame;
  ASSERT_TRUE(WaitFor([&] { return backend_->Read(&frame) == sensor::ReadStatus::kOk; }));
  emulator_->Vanish();
  const auto at_vanish = emulator_->stats();  // nothing is sent while the device is away
  ASSERT_TRUE(WaitFor([&] { return backend_->Read(&frame) == sensor::ReadStatus::kDisconnected; }));
  ASSERT_TRUE(WaitFor([&] { return !backend_->link()->connected(); }));
  const uint64_t frames_before = backend_->counters().frames;  // all the old connection gave
  EXPECT_EQ(actuator_->Write({.grip_effort = 0.3}), hand::WriteStatus::kDisconnected);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // a few failed reopen attempts
  emulator_->Return();
  ASSERT_TRUE(WaitFor([&] { return backend_->link()->connected(); }));
  const uint64_t frames = backend_->counters().frames;
  ASSERT_TRUE(WaitFor([&] {
    return backend_->Read(&frame) == sensor::ReadStatus::kOk && backend_->counters().frames > frames + 5;
  }));
  const auto counters = backend_->counters();
  EXPECT_EQ(counters.reconnects, 1u);
  EXPECT_EQ(counters.sessions, 1u);  // sequence numbers went on: the same device session
  // Frames in flight when the pty closed (sent, not yet read: how many depends on the machine's
  // pace) are lost: exactly those show up as dropped, with any the FIFO overflowed with, no more.
  emulator_->PauseFrames(true);
  ASSERT_TRUE(WaitFor([&] {
    const auto c = backend_->counters();
    const auto e = emulator_->stats();
    return c.frames + c.dropped + e.frames_trailing == e.frames_sent + e.frames_overflowed;
  }));
  const auto emu = emulator_->stats();
  EXPECT_EQ(backend_->counters().dropped,
            at_vanish.frames_sent - frames_before + emu.frames_overflowed - emu.frames_trailing);
  EXPECT_EQ(backend_->counters().corrupt, 0u);
  EXPECT_EQ(emulator_->stats().commands_before_hello, 0u);
  EXPECT_EQ(emulator_->stats().stream_starts >= 2, true);
}

TEST_F(HardwareTest, RebootStartsANewSession) {
  StartEmulator();
  StartHost();
  ASSERT_TRUE(WaitFor([&] { return backend_->counters().frames > 50; }));
  emulator_->Reboot();
  ASSERT_TRUE(WaitFor([&] { return backend_->session() == 2; }));
  const uint64_t frames = backend_->counters().frames;
  ASSERT_TRUE(WaitFor([&] { return backend_->counters().frames > frames + 10; }));  // streaming again
  const auto counters = backend_->counters();
  EXPECT_EQ(counters.sessions, 2u);
  // The restart is not a gap: the only gaps are frames the device's FIFO overflowed with (none on an
  // idle machine; on a loaded one the host falls behind and a real device would drop them too).
  EXPECT_LE(counters.dropped, emulator_->stats().frames_overflowed);
  EXPECT_EQ(counters.reconnects, 0u);
  sensor::RawFrame frame;
  ASSERT_TRUE(WaitFor([&] { return backend_->Read(&frame) == sensor::ReadStatus::kOk; }));
  EXPECT_LT(frame.time_s, 5.0);  // device time restarted
}

// A device that reboots while unplugged (a USB reset usually reboots it) and comes back: its HELLO
// numbers start again, which is a new session even when its frames seem to go on, as they do after a
// long uptime (sequence wrapped, device time past 2^31 us, so neither steps back).
TEST(HardwareRebootWhileAway, HelloNumbersStartingAgainIsANewSession) {
  HardwareConfig config;
  config.port = test_support::UniqueLinkPath("scripted");
  config.reconnect_backoff_s = 0.01;
  config.reconnect_backoff_max_s = 0.05;
  ScriptedDevice device(config.port);
  device.Appear();
  HardwareBackend backend(config, kUnits, "test_20");
  std::thread starter([&] { backend.Start(); });
  ASSERT_TRUE(device.Handshake(/*hello_seq=*/40, kUnits));
  starter.join();
  constexpr uint32_t kLongUptimeUs = 3'000'000'000u;  // 50 min
  device.SendFrames(/*first_seq=*/65530, kLongUptimeUs, /*count=*/10, kUnits);
  ASSERT_TRUE(test_support::WaitFor([&] { return backend.counters().frames == 10; }));
  EXPECT_EQ(backend.session(), 1u);

  device.Vanish();
  ASSERT_TRUE(test_support::WaitFor([&] { return !backend.link()->connected(); }));
  device.Appear();
  ASSERT_TRUE(device.Handshake(/*hello_seq=*/0, kUnits));
  ASSERT_TRUE(test_support::WaitFor([&] { return backend.link()->connected(); }));
  // Frames that look like a continuation of the old stream: only the HELLO tells.
  device.SendFrames(/*first_seq=*/4, kLongUptimeUs + 10'000, /*count=*/10, kUnits);  // 65540 wrapped
  ASSERT_TRUE(test_support::WaitFor([&] { return backend.counters().frames == 20; }));
  const auto counters = backend.counters();
  EXPECT_EQ(counters.reconnects, 1u);
  EXPECT_EQ(counters.sessions, 2u);
  EXPECT_EQ(backend.session(), 2u);
  EXPECT_EQ(counters.dropped, 0u);
  EXPECT_EQ(counters.corrupt, 0u);
}

// The late-frame rule against a device that can send any sequence number and device time: a frame
// a few numbers back is late (counted, never published); one far back is a restart.
TEST(HardwareLateFrames, AFewBackIsLateFarBackIsARestart) {
  HardwareConfig config;
  config.port = test_support::UniqueLinkPath("late");
  ScriptedDevice device(config.port);
  device.Appear();
  HardwareBackend backend(config, kUnits, "test_20");
  std::thread starter([&] { backend.Start(); });
  ASSERT_TRUE(device.Handshake(/*hello_seq=*/0, kUnits));
  starter.join();
  device.SendFrames(/*first_seq=*/65530, /*first_time_us=*/1'000'000, /*count=*/10, kUnits);  // wraps to 3
  ASSERT_TRUE(test_support::WaitFor([&] { return backend.counters().frames == 10; }));
  sensor::RawFrame frame;
  ASSERT_EQ(backend.Read(&frame), sensor::ReadStatus::kOk);
  EXPECT_EQ(frame.sequence, 3);
  // Seq 65533 again (6 back, across the wrap), 6 ms back in device time: late.
  device.SendFrames(/*first_seq=*/65533, /*first_time_us=*/1'003'000, /*count=*/1, kUnits);
  ASSERT_TRUE(test_support::WaitFor([&] { return backend.link()->reordered() == 1; }));
  EXPECT_NE(backend.Read(&frame), sensor::ReadStatus::kOk) << "a late frame was handed to the loop";
  device.SendFrames(/*first_seq=*/4, /*first_time_us=*/1'010'000, /*count=*/1, kUnits);
  ASSERT_TRUE(test_support::WaitFor([&] { return backend.counters().frames == 11; }));
  ASSERT_EQ(backend.Read(&frame), sensor::ReadStatus::kOk);
  EXPECT_EQ(frame.sequence, 4);
  auto counters = backend.counters();
  EXPECT_EQ(counters.dropped, 0u);  // not a gap of 65535
  EXPECT_EQ(counters.sessions, 1u);
  // 40 numbers back is beyond the window: the device restarted.
  device.SendFrames(/*first_seq=*/static_cast<uint16_t>(4 - 40), /*first_time_us=*/970'000, /*count=*/1,
                    kUnits);
  ASSERT_TRUE(test_support::WaitFor([&] { return backend.counters().frames == 12; }));
  counters = backend.counters();
  EXPECT_EQ(counters.sessions, 2u);
  EXPECT_EQ(backend.link()->reordered(), 1u);
  EXPECT_EQ(counters.dropped, 0u);
}

// Open, shorted and implausible channels arrive as such over the wire, and the shared readout marks
// exactly those units invalid (the hardware path never makes a force of them).
TEST_F(HardwareTest, OpenShortAndImplausibleChannelsMakeTheirUnitsInvalid) {
  EmulatorConfig config;
  config.link_path = test_support::UniqueLinkPath("faulty");
  emulator_ = std::make_unique<DeviceEmulator>(config, [](double t, bool, sensor::RawFrame* frame) {
    test_support::TestFrameSource(t, true, frame);
    frame->r1_ohm[0] = sensor::kOpenCircuitOhm;  // broken wire
    frame->r2_ohm[1] = 0.0;                      // shorted gauge
    frame->r1_ohm[2] = 50'000.0;                 // 15 x R0: no gauge reads that
  });
  emulator_->Start();
  hw_config_.port = config.link_path;
  StartHost();
  sensor::ReadoutConfig readout_config;
  readout_config.baseline_frames = 5;
  sensor::Readout readout(readout_config, kUnits, backend_->nominal_r0_ohm());
  sensor::RawFrame frame;
  sensor::ReadoutFrame out;
  int processed = 0;
  ASSERT_TRUE(WaitFor([&] {
    if (backend_->Read(&frame) == sensor::ReadStatus::kOk) {
      readout.Process(frame, &out);
      ++processed;
    }
    return processed > readout_config.baseline_frames + 2;
  }));
  EXPECT_TRUE(std::isinf(frame.r1_ohm[0]));
  EXPECT_EQ(frame.r2_ohm[1], 0.0);
  EXPECT_EQ(out.validity[0], sensor::UnitValidity::kOpen);
  EXPECT_EQ(out.validity[1], sensor::UnitValidity::kShort);
  EXPECT_EQ(out.validity[2], sensor::UnitValidity::kImplausible);
  for (int k = 3; k < kUnits; ++k) EXPECT_EQ(out.validity[k], sensor::UnitValidity::kValid) << k;
}

// The loop re-tares when the session of the frame it reads changes. A frame of the old session still
// waiting in the slot when the reboot is seen must be reported with its own session, so the new
// baseline starts with the new session's first frame.
TEST_F(HardwareTest, AFrameFromBeforeARebootKeepsItsSession) {
  StartEmulator();
  StartHost();
  ASSERT_TRUE(WaitFor([&] { return backend_->counters().frames > 20; }));
  emulator_->PauseFrames(true);
  ASSERT_TRUE(WaitHostCaughtUp(0, 0, 0));  // the last frame sent is in the slot, unread
  emulator_->Reboot();
  ASSERT_TRUE(WaitFor([&] { return backend_->link()->session() == 2; }));
  sensor::RawFrame frame;
  ASSERT_EQ(backend_->Read(&frame), sensor::ReadStatus::kOk);
  EXPECT_EQ(backend_->session(), 1u) << "an old frame was tagged with the new session";
  const double old_time_s = frame.time_s;
  emulator_->PauseFrames(false);
  ASSERT_TRUE(WaitFor([&] { return backend_->Read(&frame) == sensor::ReadStatus::kOk; }));
  EXPECT_EQ(backend_->session(), 2u);
  EXPECT_LT(frame.time_s, old_time_s);  // device time restarted
}

TEST_F(HardwareTest, FramesWithTheWrongUnitCountAreRefused) {
  StartEmulator();
  StartHost();
  ASSERT_TRUE(WaitFor([&] { return backend_->counters().frames > 5; }));
  emulator_->SetFrameUnitCount(9);
  ASSERT_TRUE(WaitFor([&] { return backend_->counters().corrupt >= 5; }));
  const std::string error = backend_->link()->last_error();
  EXPECT_NE(error.find("frames carry 9 units"), std::string::npos) << error;
  sensor::RawFrame frame;
  while (backend_->Read(&frame) == sensor::ReadStatus::kOk) {
  }
  const uint64_t frames = backend_->counters().frames;
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  EXPECT_EQ(backend_->counters().frames, frames);  // nothing of them reaches the readout
}

TEST_F(HardwareTest, ASecondEpisodeOfWrongUnitCountFramesIsReportedAgain) {
  StartEmulator();
  StartHost();
  ASSERT_TRUE(WaitFor([&] { return backend_->counters().frames > 5; }));
  emulator_->SetFrameUnitCount(9);
  ASSERT_TRUE(WaitFor([&] { return backend_->counters().corrupt >= 5; }));
  const std::string first = backend_->link()->last_error();
  EXPECT_NE(first.find("frames carry 9 units"), std::string::npos) << first;
  // The device recovers, then sends the same wrong count again: a new episode with its own message.
  emulator_->SetFrameUnitCount(kUnits);
  const uint64_t frames = backend_->counters().frames;
  ASSERT_TRUE(WaitFor([&] { return backend_->counters().frames > frames + 5; }));
  const uint64_t corrupt = backend_->counters().corrupt;
  emulator_->SetFrameUnitCount(9);
  ASSERT_TRUE(WaitFor([&] { return backend_->counters().corrupt >= corrupt + 5; }));
  const std::string second = backend_->link()->last_error();
  EXPECT_NE(second.find("frames carry 9 units"), std::string::npos) << second;
  EXPECT_NE(second, first) << "the second episode left the first one's message";
}

TEST_F(HardwareTest, CleanShutdownStopsStreamMotorAndRestoresThePort) {
  StartEmulator();
  const std::string slave = [&] {
    std::string s;
    WaitFor([&] { return !(s = emulator_->slave_path()).empty(); });
    return s;
  }();
  StartHost();
  ASSERT_EQ(actuator_->Write({.grip_effort = 0.6}), hand::WriteStatus::kOk);
  ASSERT_TRUE(WaitFor([&] { return emulator_->motor().enable; }));
  actuator_->Stop();
  backend_->Stop();
  backend_->Stop();  // twice is fine
  // The emulator reads the host's last words on its next tick.
  EXPECT_TRUE(WaitFor([&] { return emulator_->stats().stream_stops == 1u; }));
  EXPECT_TRUE(WaitFor([&] { return emulator_->stats().motor_off_commands >= 1u; }));  // by command
  EXPECT_FALSE(emulator_->motor().enable);
  // The emulator left the slave raw at its default speed; the host's 2 Mbaud must be gone.
  const int fd = ::open(slave.c_str(), O_RDWR | O_NOCTTY);
  ASSERT_GE(fd, 0);
  termios t{};
  ASSERT_EQ(tcgetattr(fd, &t), 0);
  EXPECT_NE(cfgetospeed(&t), static_cast<speed_t>(B2000000));
  ::close(fd);
}

TEST_F(HardwareTest, SeparateMotorPort) {
  StartEmulator();
  EmulatorConfig motor_config;
  motor_config.link_path = test_support::UniqueLinkPath("motor");
  motor_config.unit_count = 1;  // the hand electronics' HELLO; its unit count is not checked
  DeviceEmulator motor_device(motor_config, test_support::TestFrameSource);
  motor_device.Start();
  hw_config_.motor_port = motor_config.link_path;
  StartHost();
  ASSERT_TRUE(WaitFor([&] {
    actuator_->Write({.grip_effort = -0.25});
    return motor_device.stats().motor_commands > 0;
  }));
  EXPECT_NEAR(motor_device.motor().effort, -0.25, 1.0 / 32767);
  EXPECT_EQ(emulator_->stats().motor_commands, 0u);
  EXPECT_EQ(motor_device.stats().stream_starts, 0u);  // the motor link asks for no frames
  EXPECT_GT(backend_->counters().frames + 1, 1u);
  actuator_.reset();
  EXPECT_TRUE(WaitFor([&] { return motor_device.stats().motor_off_commands >= 1u; }));
  EXPECT_FALSE(motor_device.motor().enable);
}

}  // namespace
}  // namespace graspbed::hardware
