// Client side of the motor controller protocol (proto/irslam.dbc), as pure code:
// frames in, timestamped wheel ticks / IR samples / controller status (with its
// bumper bits confirmed) out, and command frames built on request. No socket or clock inside: the caller passes
// its own notion of "now" (robot seconds) for timeout detection.
#ifndef IRSLAM_DRIVERS_MOTOR_CLIENT_H_
#define IRSLAM_DRIVERS_MOTOR_CLIENT_H_

#include <linux/can.h>

#include <array>
#include <cstdint>
#include <optional>

#include "proto/codec.h"
#include "types/geometry.h"
#include "types/options.h"
#include "types/signals.h"

namespace irslam::drivers {

// Unwraps a wrapping 16-bit counter into a monotonic-ish 64-bit value by taking
// the nearest representative of each new sample (valid while consecutive samples
// differ by less than half the range).
class Unwrapper16 {
 public:
  int64_t Update(uint16_t raw);
  // What Update(raw) would return, without taking the sample.
  int64_t Peek(uint16_t raw) const;
  // The next sample becomes `base` + 0 (used after a controller reset).
  void Rebase(int64_t base) {
    rebase_ = true;
    base_ = base;
  }
  bool initialized() const { return initialized_; }
  int64_t value() const { return value_; }

 private:
  bool initialized_ = false;
  bool rebase_ = false;
  int64_t base_ = 0;
  uint16_t last_raw_ = 0;
  int64_t value_ = 0;
};

// One message type's sequence number and time stamp, checked against each other:
// consecutive frames are `period` apart, so a stamp whose step disagrees with the
// sequence step (a flipped bit) is caught even when it is close to the clock.
// The period is learnt from the frames themselves.
class SeqStampCheck {
 public:
  // True when (seq, stamp_ms) is consistent with the last accepted frame (or
  // nothing is known yet); then it becomes the last accepted one.
  bool Accept(uint8_t seq, int64_t stamp_ms);
  void Reset() { *this = SeqStampCheck(); }
  double period_ms() const { return period_ms_; }

 private:
  std::optional<uint8_t> seq_;
  int64_t stamp_ = 0;
  double period_ms_ = 0;
  int learnt_ = 0;      // period samples so far
  int rejected_ = 0;    // in a row
};

struct MotorClientCounters {
  uint64_t encoder_frames = 0;
  uint64_t ir_samples = 0;
  uint64_t status_frames = 0;
  uint64_t unknown_id = 0;
  uint64_t wrong_dlc = 0;
  uint64_t ignored = 0;         // well-formed frames not meant for us (e.g. other commands)
  uint64_t seq_gap_encoder = 0;
  uint64_t seq_gap_ir = 0;
  uint64_t seq_gap_status = 0;
  uint64_t ir_unpaired = 0;     // IR_A/IR_B halves that never found their partner
  uint64_t controller_resets = 0;  // the controller's clock went back (it restarted)
  // Implausible data, never passed on (see MotorClient::FrameTime, HandleEncoder).
  uint64_t duplicate = 0;           // a frame whose time was already seen
  uint64_t stale = 0;               // a frame older than one already taken (reordered/late)
  uint64_t implausible_time = 0;    // a time stamp far from where the controller's clock is
  uint64_t implausible_counts = 0;  // a count jump impossible at the maximum wheel speed
  uint64_t clock_jumps = 0;         // the controller's clock re-anchored forward
  uint64_t bumper_unconfirmed = 0;  // a CTRL_STATUS bumper bit set in one frame only
};

struct MotorClientOptions {
  // Encoder/status silence beyond this (robot seconds) means the controller is lost.
  double timeout_s = 0.1;
  // The fastest a wheel's count can change (counts/s); 0 = not checked. RobotCore
  // sets it from the robot geometry ([robot].max_wheel_speed_mps x
  // [controller].plausible_speed_factor).
  double max_counts_per_s = 0;
  double plausible_speed_factor = 2.0;
};

// Config section [controller] (with the core's heartbeat_period_s).
options::Table<MotorClientOptions> MotorClientKeys();

class MotorClient {
 public:
  struct Event {
    std::optional<WheelTicks> ticks;
    std::optional<std::array<uint16_t, kNumIrSensors>> ir_adc;
    double ir_t = 0;
    std::optional<proto::ControllerStatus> status;
    // With status: the bumper bits confirmed so far (see bumpers()).
    std::optional<uint8_t> bumpers;
  };

  explicit MotorClient(MotorClientOptions options) : options_(options) {}

  // Decodes one frame received at robot time `now_s`.
  Event Handle(const can_frame& frame, double now_s);

  can_frame MakeCommand(const WheelCommand& cmd);
  can_frame MakeHeartbeat(uint8_t daemon_state);

  // True while encoder frames and controller status arrive within timeout_s.
  bool ControllerAlive(double now_s) const;
  // Why the controller is considered lost (empty when alive).
  const char* LossReason(double now_s) const;

  const MotorClientCounters& counters() const { return counters_; }
  const std::optional<proto::ControllerStatus>& last_status() const { return last_status_; }
  // The controller's bumper bits (kBumperLeft, kBumperRight) that count: a bit
  // counts when two CTRL_STATUS frames in a row (50 ms apart) carry it. A real
  // contact lasts (the robot is stopped against the obstacle); a flipped bit does
  // not, and is counted (bumper_unconfirmed).
  uint8_t bumpers() const { return bumpers_; }

 private:
  // The controller time of a stamp in seconds, or nullopt when the stamp is
  // implausible (counted). Re-anchors after kConfirm consistent implausible stamps.
  std::optional<double> ControllerTime(uint16_t stamp_ms, double now_s);
  static constexpr int kConfirm = 3;
  void CheckSeq(std::optional<uint8_t>* last, uint8_t seq, uint64_t* gaps);
  void ConfirmBumpers(uint8_t raw);
  // A frame's controller time, or nullopt when it is rejected (counted): its
  // stamp disagrees with its sequence number, is implausible, or is not after
  // `last` (a duplicate or stale frame).
  std::optional<double> FrameTime(SeqStampCheck* check, uint8_t seq, uint16_t stamp_ms,
                                  double now_s, std::optional<double>* last);
  // Handle's parts, one per message.
  void HandleEncoder(const proto::EncoderCounts& e, double now_s, Event* ev);
  void HandleIrA(const proto::IrA& a, double now_s);
  void HandleIrB(const proto::IrB& b, Event* ev);
  void HandleStatus(const proto::ControllerStatus& s, double now_s, Event* ev);

  MotorClientOptions options_;
  MotorClientCounters counters_;
  Unwrapper16 clock_;
  Unwrapper16 left_;
  Unwrapper16 right_;
  std::optional<uint8_t> seq_encoder_, seq_ir_, seq_status_;
  std::optional<proto::IrA> pending_ir_a_;
  std::optional<proto::ControllerStatus> last_status_;
  uint8_t bumpers_ = 0;  // confirmed
  uint8_t last_status_bumpers_ = 0, bumpers_before_ = 0;  // raw, of the last two status frames
  double host_at_clock_ = 0;                 // host time when the clock last advanced
  std::optional<uint16_t> suspect_stamp_;    // the last implausible stamp ...
  int suspects_ = 0;                         // ... and how many agreeing ones in a row
  int count_suspects_ = 0;                   // encoder frames with impossible counts in a row
  std::optional<double> last_enc_t_, last_ir_t_, last_status_t_;
  std::optional<uint8_t> last_ir_pair_seq_;
  SeqStampCheck enc_check_, ir_check_, status_check_;
  double last_encoder_rx_ = -1e9;
  double last_status_rx_ = -1e9;
  uint8_t cmd_seq_ = 0;
  uint8_t hb_seq_ = 0;
};

}  // namespace irslam::drivers

#endif  // IRSLAM_DRIVERS_MOTOR_CLIENT_H_
