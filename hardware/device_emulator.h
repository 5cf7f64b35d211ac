#pragma once
/// DeviceEmulator: a tactile readout and hand electronics in software, behind a pseudo-terminal. It
/// speaks docs/protocol.md as the device does: HELLO on connect and every second, TACTILE_FRAMEs at the
/// nominal rate (from a frame-source callback) while streaming, MOTOR_COMMANDs to a motor-sink
/// callback, the 100 ms motor watchdog, STREAM_CONTROL; as a version-2 device (the default) also a
/// HAND before each frame (from a hand-source callback) once the host has chosen version 2 with
/// PROTOCOL_SELECT, and as a version-1 device (EmulatorConfig::protocol_version) none of that. The pty's
/// slave is exposed at a symlink so a host opens it like a real port. Fault-injection knobs reproduce every
/// fault the host must survive. No MuJoCo here: `graspbed emulate` plugs the simulation in through the
/// callbacks.

#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

#include "hand/hand_state.h"
#include "sensor/raw_frame.h"
#include "hardware/protocol.h"
#include "hardware/stream_decoder.h"

namespace graspbed::hardware {

struct EmulatorConfig {
  std::string link_path;          ///< where the symlink to the pty slave is created (removed on Stop)
  int unit_count = 20;            ///< units reported in HELLO and carried in frames (1..64)
  int frame_rate_hz = 1000;       ///< nominal frame rate [Hz]
  double hello_period_s = 1.0;    ///< HELLO repeat period while a host is connected [s]
  double connect_delay_s = 0.02;  ///< HELLO this long after a host opens the port [s]
  double watchdog_s = 0.1;        ///< motor off when no MOTOR_COMMAND for this long [s]
  uint16_t firmware_version = 0x0100;
  double nominal_r0_ohm = 3400.0;  ///< reported in HELLO [Ohm]
  /// The highest protocol version the device speaks (1 or 2). 1: its HELLO says 0 in byte 7 as a
  /// version-1 device does, it never sends HAND and takes PROTOCOL_SELECT for an unknown packet.
  int protocol_version = kProtocolVersion;

  /// @throws common::ConfigError naming the field (key path) and value.
  void Validate() const;
};

/// The grip motor as the device drives it.
struct EmulatedMotor {
  double effort = 0.0;  ///< [-1, 1], + closes
  bool enable = false;  ///< false: motor off
  bool brake = false;
};

/// What the emulator has done; read with stats().
struct EmulatorStats {
  uint64_t frames_sent = 0;        ///< frames written to the pty (including corrupted and late ones)
  uint64_t frames_dropped = 0;     ///< frames skipped by DropFrames (sequence numbers still advance)
  uint64_t frames_corrupted = 0;   ///< frames sent with a flipped byte or truncated (TruncateNextFrame)
  uint64_t frames_overflowed = 0;  ///< frames not sent because the host did not read (pty full)
  /// Frames sent after a newer intact frame (ReorderFrames): what the host must count as reordered. A
  /// held-back frame that no newer intact frame overtook went out in order and is not counted.
  uint64_t frames_reordered = 0;
  uint64_t garbage_packets = 0;  ///< delimited garbage blocks sent (InjectGarbage with delimited = true)
  /// Sequence numbers used after the newest intact frame sent (dropped, corrupted or overflowed ones
  /// at the end of the stream so far): the host learns of them as a gap only when a newer frame comes.
  uint64_t frames_trailing = 0;
  uint64_t hellos_sent = 0;
  uint64_t motor_commands = 0;      ///< valid MOTOR_COMMANDs received
  uint64_t motor_off_commands = 0;  ///< of those, with enable = 0
  /// Longest time between two MOTOR_COMMANDs received while the motor ran [s] (what the watchdog sees).
  double max_command_interval_s = 0.0;
  uint64_t commands_before_hello = 0;  ///< host packets that arrived before our first HELLO of a connection
  uint64_t stream_starts = 0;
  uint64_t stream_stops = 0;
  uint64_t watchdog_trips = 0;
  uint64_t connects = 0;      ///< times a host opened the port
  uint64_t vanishes = 0;      ///< Vanish() calls that closed an open pty
  uint64_t settles = 0;       ///< Settle() calls
  uint64_t settles_unconfirmed = 0;  ///< of those, not confirmed by the host (timeout, no host)
  uint64_t host_corrupt = 0;  ///< host packets refused by our decoder
  uint64_t host_unknown = 0;  ///< host packets of a type this device's version does not define
  uint64_t selects = 0;       ///< PROTOCOL_SELECTs taken (version 2 chosen by the host)
  uint64_t hand_sent = 0;     ///< HANDs written to the pty (including corrupted ones)
  uint64_t hand_corrupted = 0;   ///< HANDs sent with a flipped byte (CorruptHand)
  uint64_t hand_malformed = 0;   ///< valid-CRC HANDs with a bad digit count sent (InjectMalformedHand)
  uint64_t hand_dropped = 0;     ///< HANDs skipped by DropHand (sequence numbers still advance)
  uint64_t hand_overflowed = 0;  ///< HANDs not sent because the host did not read
  uint16_t last_frame_sequence = 0;
  bool streaming = false;
  bool host_connected = false;
};

class DeviceEmulator {
 public:
  /// Fills `frame` (unit_count preset) with R1/R2 [Ohm] for device time `device_time_s`. Called once
  /// per frame period on the emulator thread, streaming or not (so a simulation keeps real time);
  /// `streaming` tells whether a host currently asks for frames.
  using FrameSource = std::function<void(double device_time_s, bool streaming, sensor::RawFrame* frame)>;
  /// Receives the motor state whenever it changes (command, watchdog, stream loss, reboot).
  using MotorSink = std::function<void(const EmulatedMotor& motor)>;
  /// Fills `state` with the hand's proprioception at device time `device_time_s` [s]; false when it
  /// has none (no HAND is sent). Called on the emulator thread before each frame while a host that
  /// chose version 2 streams.
  using HandSource = std::function<bool(double device_time_s, hand::HandState* state)>;

  DeviceEmulator(const EmulatorConfig& config, FrameSource source, MotorSink sink = {});
  ~DeviceEmulator();
  DeviceEmulator(const DeviceEmulator&) = delete;
  DeviceEmulator& operator=(const DeviceEmulator&) = delete;

  /// The hand's proprioception for HAND packets (call before Start(); none: no HAND is sent).
  void SetHandSource(HandSource source) { hand_source_ = std::move(source); }

  /// Creates the pty and the symlink, starts the device thread. Throws std::runtime_error when the
  /// link path exists and is not a symlink, or the pty cannot be made.
  void Start();
  /// Stops the thread, closes the pty, removes the symlink. Safe to call twice.
  void Stop();

  // Fault injection (thread-safe; applied to the next frames sent).
  /// Sends the next `count` frames with one byte flipped (the host sees CRC/COBS errors).
  void CorruptFrames(int count);
  /// Skips the next `count` frames; their sequence numbers are used up (the host sees a gap).
  void DropFrames(int count);
  /// Writes `bytes` random non-zero bytes before the next frame, followed by 0x00 when `delimited`.
  void InjectGarbage(int bytes, bool delimited);
  /// Writes `bytes` non-zero bytes and then a delimiter (longer than the maximum packet when > 515).
  void InjectOversize(int bytes);
  /// Sends the next `count` HANDs with one byte flipped (the host sees CRC/COBS errors: corrupt).
  void CorruptHand(int count);
  /// Skips the next `count` HANDs; their sequence numbers are used up (the host counts a gap).
  void DropHand(int count);
  /// Sends `count` HANDs with a valid CRC that claim 3 digits (the host refuses them: corrupt, and
  /// HandCounters::malformed), in place of the next ones.
  void InjectMalformedHand(int count);
  /// Sends a valid packet of undefined type `type` (version 1).
  void InjectUnknownType(uint8_t type);
  /// Sends a valid-CRC HELLO with protocol version `version`.
  void InjectBadVersion(uint8_t version);
  /// Truncates the next frame by `bytes` bytes before its delimiter (bytes lost mid-packet).
  void TruncateNextFrame(int bytes);
  /// Sends frames out of order: each of the next `count` intact frames is held back and sent right
  /// after the `later` frames that follow it (their sequence numbers; 1 = swapped with the next), with
  /// its own sequence number and device time. One frame is held at a time. The host sees an older
  /// frame after newer ones (docs/protocol.md, "Late frames"); frames_reordered counts them.
  void ReorderFrames(int count, int later = 1);
  /// Pauses (true) or resumes the frame stream without telling the host (stale data).
  void PauseFrames(bool paused);
  /// Brings the link to a known state before a disconnect or the end of a soak: pauses the frame
  /// stream (PauseFrames(true); no sample taken, no sequence number used), sends a held-back frame
  /// now, then a HELLO, and waits up to `timeout_s` until the host has answered every HELLO of this
  /// connection with STREAM_CONTROL start. The host answers each HELLO it decodes, in order, so it
  /// has then read every byte sent before: nothing is in flight. Blocks the caller (not the device
  /// thread). True when confirmed; false (counted in settles_unconfirmed) on timeout, when no host
  /// is connected, or when a HELLO of this connection was lost (the host flushes its input when it
  /// opens the port: a HELLO sent before that is never answered). The stream stays paused.
  bool Settle(double timeout_s);
  /// Frames carry `unit_count` units (0: as configured), HELLO keeps the configured count.
  void SetFrameUnitCount(int unit_count);
  /// The device disappears: the pty closes (the host reads EIO/POLLHUP) and the symlink goes.
  void Vanish();
  /// The device comes back on a new pty behind the same symlink; it waits for a host again.
  void Return();
  /// The device restarts: sequence numbers and device time start again from 0, streaming stops,
  /// the motor is off, and a HELLO follows at once.
  void Reboot();

  EmulatorStats stats() const;
  EmulatedMotor motor() const;
  /// The pty slave the symlink points to ("" while vanished).
  std::string slave_path() const;

 private:
  void Run();
  void Tick(int64_t now_ns);
  void CheckWatchdog(int64_t now_ns);
  void OpenPty();
  void ClosePty();
  bool Queue(std::span<const uint8_t> bytes);
  void QueueHello();
  void SendFrame(std::span<const uint8_t> bytes, uint64_t index, bool intact);
  void ReleaseHeld();
  void Flush();
  void HandleHostPacket(const DecodedPacket& packet, int64_t now_ns);
  void SendHand(double device_time_s, uint32_t device_time_us);
  void SetMotor(const EmulatedMotor& motor);

  const EmulatorConfig config_;
  FrameSource source_;
  MotorSink sink_;
  HandSource hand_source_;
  std::thread thread_;
  std::atomic<bool> running_{false};

  mutable std::mutex mutex_;  // everything below; held by the device thread for one tick
  int master_fd_ = -1;
  std::string slave_path_;
  bool symlink_made_ = false;
  StreamDecoder decoder_;
  DecodedPacket packet_;
  sensor::RawFrame frame_;
  TactileFramePacket wire_frame_;
  hand::HandState hand_state_;
  HandPacket wire_hand_;
  uint16_t hand_seq_ = 0;
  int selected_version_ = 1;  // the version the host chose on this connection (1 until it selects)
  int corrupt_hand_ = 0;
  int drop_hand_ = 0;
  int malformed_hand_ = 0;
  std::array<uint8_t, 65536> out_{};
  size_t out_size_ = 0;
  uint64_t tick_ = 0;
  uint64_t time_base_tick_ = 0;
  uint16_t frame_seq_ = 0;
  uint64_t frame_index_ = 0;              // sequence numbers used, never wrapping (reset by Reboot)
  bool newest_intact_valid_ = false;      // an intact frame was queued in this session
  uint64_t newest_intact_index_ = 0;      // the newest of them
  uint64_t hellos_this_connection_ = 0;   // HELLOs queued since the host opened the port
  uint64_t answers_this_connection_ = 0;  // STREAM_CONTROL starts received since then
  uint16_t hello_seq_ = 0;
  bool hello_sent_this_connection_ = false;
  int64_t hello_due_ns_ = 0;
  int64_t last_motor_ns_ = 0;
  bool last_command_enabled_ = false;
  EmulatedMotor motor_;
  EmulatorStats stats_;
  uint32_t rng_ = 0x12345678u;
  // Pending faults.
  int corrupt_frames_ = 0;
  int drop_frames_ = 0;
  int truncate_bytes_ = 0;
  int reorder_frames_ = 0;  // frames still to hold back
  int reorder_later_ = 1;
  std::array<uint8_t, kMaxWirePacketSize> held_{};  // the held-back frame on the wire
  size_t held_size_ = 0;                            // 0: none held
  uint64_t held_index_ = 0;
  int held_countdown_ = 0;  // sequence numbers still to pass before it is sent
  bool paused_ = false;
  int frame_unit_count_ = 0;
};

}  // namespace graspbed::hardware
