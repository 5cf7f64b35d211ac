#pragma once
/// SerialLink: one serial port and the I/O thread that owns it. It opens the port, waits for the
/// device's HELLO, checks the unit count, starts the stream, decodes packets, keeps the counters,
/// publishes the newest frame for the control loop, sends motor commands, and survives the faults of
/// docs/protocol.md ("What the host must survive"): corrupt bytes, gaps, reboots, a vanishing device.
/// HardwareBackend and HardwareActuator (hardware_backend.h) are thin faces on one or two links.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "hand/hand_command.h"
#include "hand/hand_state.h"
#include "sensor/raw_frame.h"
#include "sensor/tactile_backend.h"
#include "hardware/hardware_config.h"
#include "hardware/loop_latency.h"
#include "hardware/protocol.h"
#include "hardware/serial_port.h"
#include "hardware/stream_decoder.h"

namespace graspbed::hardware {

/// What a link carries.
enum class LinkRole {
  kSensorAndMotor,  ///< tactile frames in, motor commands out (one port for both)
  kSensor,          ///< tactile frames only
  kMotor,           ///< motor commands only (the hand electronics on a port of their own)
};

/// Late frames (docs/protocol.md, "Late frames"): a frame at most this many sequence numbers behind
/// the newest accepted one, and behind it in device time by at most this many nominal frame periods,
/// was delayed on its way (reordered); further back, or not back in time, the device restarted.
inline constexpr int kLateFrameWindow = 32;

/// How a frame's sequence number and device time relate to the newest accepted frame's.
enum class FrameOrder {
  kNext,     ///< the next one: +1
  kGap,      ///< newer, with sequence numbers missing in between (counted dropped)
  kLate,     ///< older, within kLateFrameWindow: reordered; counted, never used
  kRestart,  ///< duplicate, or backwards beyond the window: the device restarted (new session)
};

/// Classifies a frame by `sequence_step` = int16(sequence - newest's) and `time_step_us` =
/// int32(device time - newest's) [us], with `period_us` the nominal frame period (from HELLO).
FrameOrder ClassifyFrameOrder(int sequence_step, int64_t time_step_us, int64_t period_us);

/// One decoded frame with the device session it belongs to (for loggers that see every frame).
struct TappedFrame {
  sensor::RawFrame frame;
  uint64_t session = 0;
  /// The newest HAND decoded before the frame, its time_s on the device's clock [s] (digit_count 0:
  /// none on this connection, e.g. a version-1 device).
  hand::HandState hand;
};

/// What the link has seen of HAND packets (protocol version 2) since Start().
struct HandCounters {
  uint64_t messages = 0;   ///< HAND packets accepted (published to the hand sensor)
  uint64_t malformed = 0;  ///< valid CRC, refused for their length or digit/joint count (also in corrupt)
  uint64_t dropped = 0;    ///< sequence numbers missing between accepted HANDs
  uint64_t late = 0;       ///< older than the newest accepted one: discarded
};

class SerialLink {
 public:
  /// `expected_units`: units of the configured layout (ignored for kMotor); `layout_name` for messages.
  SerialLink(std::string path, const HardwareConfig& config, LinkRole role, int expected_units,
             std::string layout_name);
  ~SerialLink();
  SerialLink(const SerialLink&) = delete;
  SerialLink& operator=(const SerialLink&) = delete;

  /// Opens the port (PortError: missing, permission, busy), starts the I/O thread and waits for the
  /// first HELLO. Throws std::runtime_error when no HELLO arrives within hello_timeout_s or its unit
  /// count does not match the layout. Then sends STREAM_CONTROL start (sensor roles).
  void Start();
  /// Stream stop, motor off, drain, restore the port settings, close, join. Safe to call twice.
  void Stop();

  /// Copies the newest frame when it is newer than `*last_id` (updating it), and the device session
  /// it belongs to into `*session` when given. Never blocks: when the I/O thread is publishing right
  /// now, returns false and the frame is taken at the next call.
  bool TryTakeFrame(sensor::RawFrame* frame, uint64_t* last_id, uint64_t* session = nullptr);
  /// Blocks up to `timeout_s` until a frame newer than `last_id` is published (for drivers that tick
  /// on frame arrival; never called by the control loop itself). True when one is there.
  bool WaitForFrame(uint64_t last_id, double timeout_s);
  /// Frames published so far (compare with WaitForFrame's `last_id`).
  uint64_t published() const { return published_.load(std::memory_order_acquire); }
  /// Seconds since the newest valid frame arrived (since the handshake when none has).
  double SecondsSinceLastFrame() const;
  /// True while the port is open, the handshake is done and the device was not refused.
  bool connected() const { return connected_.load(std::memory_order_acquire); }
  /// Device session: 1 after the first handshake, +1 on every detected reboot.
  uint64_t session() const { return counter_sessions_.load(std::memory_order_acquire); }
  sensor::BackendCounters counters() const;
  /// Late frames (FrameOrder::kLate): arrived after a newer one, counted here and in `dropped` (their
  /// sequence numbers were missing when the newer frame came), never published or tapped.
  uint64_t reordered() const { return counter_reordered_.load(std::memory_order_acquire); }
  /// The newest HELLO (firmware, unit count, nominal rate and R0).
  HelloPacket hello() const;
  /// The protocol version chosen with the device on the current connection: the lower of its HELLO's
  /// and kProtocolVersion (PROTOCOL_SELECT sent when 2); 0 before a HELLO.
  uint8_t protocol_version() const { return protocol_version_.load(std::memory_order_acquire); }
  /// Copies the newest hand state (HAND packet) when it is newer than `*last_id` (updating it), with
  /// when it was decoded (steady clock [ns]) into `*arrival_ns`; its time_s is the device's [s].
  /// Never blocks (false when the I/O thread holds it; taken at the next call), never allocates.
  bool TryTakeHand(hand::HandState* state, uint64_t* last_id, int64_t* arrival_ns);
  HandCounters hand_counters() const;
  /// The newest refusal or fault worth telling the user ("" when none).
  std::string last_error() const;
  const std::string& path() const { return path_; }
  const HardwareConfig& config() const { return config_; }

  /// Keeps a copy of every decoded frame in a ring of `capacity` (allocated now, before Start());
  /// frames that do not fit are counted in tap_overflows().
  void EnableTap(size_t capacity);
  /// Takes the oldest tapped frame; false when none.
  bool PopTap(TappedFrame* out);
  uint64_t tap_overflows() const { return tap_overflows_.load(); }

  /// Queues `command` as the next MOTOR_COMMAND (the newest wins). kDisconnected, and nothing is
  /// queued, while no HELLO has been seen on the current connection. Never blocks. `frame_arrival_ns`:
  /// when the frame the command answers was decoded (taken_frame_arrival_ns() of the sensor's link;
  /// 0: none), for the loop latency.
  hand::WriteStatus SendMotor(const hand::HandCommand& command, int64_t frame_arrival_ns = 0);
  /// Queues motor off and waits up to `timeout_s` until it has been written.
  void MotorOff(double timeout_s);
  /// MOTOR_COMMAND packets written since Start().
  uint64_t motor_commands_sent() const { return motor_sent_.load(); }

  /// Records the loop latency of up to `frames` frames (allocated now, before Start()): for each frame
  /// a command answers, the time from the frame's decode to that command's write() returning.
  void EnableLatencyRecording(size_t frames) { latency_.Reserve(frames); }
  /// The recorded figures (after Stop()).
  LatencySummary latency() const { return latency_.Summary(); }
  /// When the newest frame TryTakeFrame() returned was decoded (steady clock [ns]; 0 before any).
  int64_t taken_frame_arrival_ns() const { return taken_arrival_ns_.load(std::memory_order_acquire); }

 private:
  void Run();
  void Wake();
  void HandlePacket(const DecodedPacket& packet);
  void HandleHello(const HelloPacket& hello);
  void HandleFrame(const TactileFramePacket& frame);
  void HandleHand(const HandPacket& hand);
  void Tap(uint64_t session);
  void SendSelect(uint8_t version);
  void NewSession();
  void OnLost();
  void SendPendingMotor();
  void SendStream(bool start);
  bool WritePacket(std::span<const uint8_t> bytes);
  void CheckStale();
  void SetError(const std::string& message);
  void Shutdown();
  bool has_sensor() const { return role_ != LinkRole::kMotor; }
  bool has_motor() const { return role_ != LinkRole::kSensor; }
  int64_t NowNs() const;

  const std::string path_;
  const HardwareConfig config_;
  const LinkRole role_;
  const int expected_units_;
  const std::string layout_name_;

  SerialPort port_;
  StreamDecoder decoder_;
  DecodedPacket packet_;      // decoder output, reused
  sensor::RawFrame scratch_;  // converted frame before publishing, reused
  int wake_fd_ = -1;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  bool started_ = false;

  // I/O-thread state.
  bool handshake_ = false;       // HELLO seen on the current connection
  bool ever_connected_ = false;  // a handshake happened before (so the next one is a reconnect)
  bool have_last_frame_ = false;
  uint16_t last_frame_seq_ = 0;
  uint32_t last_frame_time_us_ = 0;
  int64_t frame_period_us_ = 1000;  // nominal, from the newest HELLO's rate
  bool have_last_hello_ = false;
  uint16_t last_hello_seq_ = 0;
  bool stale_ = false;
  uint16_t motor_seq_ = 0;
  uint16_t stream_seq_ = 0;
  uint16_t select_seq_ = 0;
  bool have_last_hand_ = false;
  uint16_t last_hand_seq_ = 0;
  hand::HandState hand_scratch_;  // converted HAND before publishing; its time on the device clock
  uint64_t extra_corrupt_ = 0;  // frames refused for a wrong unit count
  // Unit count of the current episode of refused frames (its message is set); -1 outside one.
  int last_refused_units_ = -1;
  uint64_t extra_unknown_ = 0;  // host-to-device packets echoed back to us

  // Shared with other threads.
  std::atomic<bool> connected_{false};
  std::atomic<bool> refused_{false};
  std::atomic<int64_t> last_frame_ns_{0};
  // Low half: bit 31 pending, bit 30 the high half is set; bits 8..23 effort; bits 0..7 flags. High half:
  // when the frame the command answers was decoded [us, modulo 2^32].
  std::atomic<uint64_t> pending_motor_{0};
  std::atomic<uint64_t> motor_sent_{0};
  std::atomic<uint8_t> protocol_version_{0};
  std::atomic<uint64_t> hand_messages_{0}, hand_dropped_{0}, hand_late_{0}, decoder_hand_errors_{0};
  std::atomic<uint64_t> counter_frames_{0}, counter_corrupt_{0}, counter_dropped_{0}, counter_unknown_{0},
      counter_reconnects_{0}, counter_stale_{0}, counter_sessions_{0}, counter_reordered_{0};

  mutable std::mutex frame_mutex_;  // guards slot_, slot_id_, slot_session_; the loop only try_locks it
  sensor::RawFrame slot_;
  uint64_t slot_id_ = 0;
  uint64_t slot_session_ = 0;
  int64_t slot_arrival_ns_ = 0;                  // when the slot's frame was decoded
  std::atomic<int64_t> taken_arrival_ns_{0};     // the same for the frame the loop took last
  uint32_t last_answered_arrival_us_ = 0;        // I/O thread: the frame whose latency was recorded last
  bool answered_any_ = false;
  LatencyRecorder latency_;
  std::atomic<uint64_t> published_{0};
  mutable std::mutex hand_mutex_;  // guards hand_slot_*; the loop only try_locks it
  hand::HandState hand_slot_;
  uint64_t hand_slot_id_ = 0;
  int64_t hand_slot_arrival_ns_ = 0;
  std::atomic<uint64_t> hand_published_{0};
  std::mutex wait_mutex_;
  std::condition_variable frame_cv_;

  mutable std::mutex info_mutex_;  // guards hello_, error_, and the start handshake
  std::condition_variable info_cv_;
  HelloPacket hello_;
  std::string error_;

  std::mutex tap_mutex_;
  std::vector<TappedFrame> tap_;
  size_t tap_head_ = 0, tap_size_ = 0;
  std::atomic<uint64_t> tap_overflows_{0};
};

}  // namespace graspbed::hardware
