#include "drivers/motor_client.h"

#include <algorithm>
#include <cmath>

namespace irslam::drivers {

int64_t Unwrapper16::Update(uint16_t raw) {
  if (!initialized_ || rebase_) {
    value_ = rebase_ ? base_ : raw;
    initialized_ = true;
    rebase_ = false;
  } else {
    const auto delta = static_cast<int16_t>(static_cast<uint16_t>(raw - last_raw_));
    value_ += delta;
  }
  last_raw_ = raw;
  return value_;
}

int64_t Unwrapper16::Peek(uint16_t raw) const {
  if (!initialized_ || rebase_) return rebase_ ? base_ : raw;
  return value_ + static_cast<int16_t>(static_cast<uint16_t>(raw - last_raw_));
}

namespace {
// A stamp may lag the controller's clock by this much (an IR sample taken before
// the last encoder frame was sent) and lead it by this much beyond the host's own
// elapsed time (frames queued behind a stalled reader).
constexpr double kMaxLagS = 0.5;
constexpr double kMaxLeadS = 0.5;
// Impossible count jumps are judged with this much slack (quantisation, jitter).
constexpr double kCountSlack = 20;
}  // namespace

bool SeqStampCheck::Accept(uint8_t seq, int64_t stamp_ms) {
  if (seq_) {
    const int dseq = static_cast<uint8_t>(seq - *seq_);
    const int64_t dstamp = stamp_ms - stamp_;
    if (learnt_ >= 8 && dseq > 0 && dseq < 64) {
      const double expected = dseq * period_ms_;
      const double tolerance = std::max(3.0, 0.5 * period_ms_) + 0.1 * expected;
      if (std::abs(static_cast<double>(dstamp) - expected) > tolerance) {
        // Three in a row that disagree: the controller changed (restarted,
        // another rate): start again from this frame.
        if (++rejected_ < 3) return false;
        Reset();
      }
    }
    if (seq_ && dseq == 1 && dstamp > 0 && dstamp < 1000) {
      period_ms_ = learnt_ == 0 ? static_cast<double>(dstamp) : 0.9 * period_ms_ + 0.1 * static_cast<double>(dstamp);
      ++learnt_;
    }
  }
  rejected_ = 0;
  seq_ = seq;
  stamp_ = stamp_ms;
  return true;
}

std::optional<double> MotorClient::ControllerTime(uint16_t stamp_ms, double now_s) {
  if (!clock_.initialized()) {
    host_at_clock_ = now_s;
    return static_cast<double>(clock_.Update(stamp_ms)) * 1e-3;
  }
  const int64_t before = clock_.value();
  const double dt = static_cast<double>(clock_.Peek(stamp_ms) - before) * 1e-3;
  const double host_dt = std::max(0.0, now_s - host_at_clock_);
  if (dt >= -kMaxLagS && dt <= host_dt + kMaxLeadS) {
    suspects_ = 0;
    suspect_stamp_.reset();
    if (dt > 0) host_at_clock_ = now_s;
    return static_cast<double>(clock_.Update(stamp_ms)) * 1e-3;
  }
  // Far from the clock: a corrupted stamp (dropped), or the controller restarted
  // / its clock jumped. Only when kConfirm stamps in a row agree with each other
  // on the new clock is it taken: time and wheel counts then carry on
  // continuously from where they were.
  ++counters_.implausible_time;
  const bool agrees = suspect_stamp_ &&
                      std::abs(static_cast<int16_t>(static_cast<uint16_t>(stamp_ms - *suspect_stamp_))) <= 500;
  suspects_ = agrees ? suspects_ + 1 : 1;
  suspect_stamp_ = stamp_ms;
  if (suspects_ < kConfirm) return std::nullopt;
  if (dt < 0) {
    ++counters_.controller_resets;
  } else {
    ++counters_.clock_jumps;
  }
  suspects_ = 0;
  suspect_stamp_.reset();
  clock_.Rebase(before + std::max<int64_t>(1, std::llround(host_dt * 1000)));
  host_at_clock_ = now_s;
  left_.Rebase(left_.value());
  right_.Rebase(right_.value());
  seq_encoder_.reset();
  seq_ir_.reset();
  seq_status_.reset();
  pending_ir_a_.reset();
  last_ir_pair_seq_.reset();
  enc_check_.Reset();
  ir_check_.Reset();
  status_check_.Reset();
  return static_cast<double>(clock_.Update(stamp_ms)) * 1e-3;
}

void MotorClient::ConfirmBumpers(uint8_t raw) {
  bumpers_ = raw & last_status_bumpers_;
  const auto new_bits = static_cast<uint8_t>(last_status_bumpers_ & ~bumpers_before_);
  if (new_bits & ~raw) ++counters_.bumper_unconfirmed;  // set in one frame only
  bumpers_before_ = last_status_bumpers_;
  last_status_bumpers_ = raw;
}

void MotorClient::CheckSeq(std::optional<uint8_t>* last, uint8_t seq, uint64_t* gaps) {
  if (last->has_value() && static_cast<uint8_t>(**last + 1) != seq) ++*gaps;
  *last = seq;
}

MotorClient::Event MotorClient::Handle(const can_frame& frame, double now_s) {
  Event ev;
  const proto::DecodeResult r = proto::Decode(frame);
  if (!r.ok()) {
    if (r.error == proto::DecodeError::kWrongDlc) {
      ++counters_.wrong_dlc;
    } else {
      ++counters_.unknown_id;
    }
    return ev;
  }
  if (const auto* e = std::get_if<proto::EncoderCounts>(&r.message)) {
    HandleEncoder(*e, now_s, &ev);
  } else if (const auto* a = std::get_if<proto::IrA>(&r.message)) {
    HandleIrA(*a, now_s);
  } else if (const auto* b = std::get_if<proto::IrB>(&r.message)) {
    HandleIrB(*b, &ev);
  } else if (const auto* s = std::get_if<proto::ControllerStatus>(&r.message)) {
    HandleStatus(*s, now_s, &ev);
  } else {
    ++counters_.ignored;
  }
  return ev;
}

// Checked in this order, each rejection counted by reason; nothing rejected is
// passed on (so it never reaches SLAM): implausible time stamp, duplicate or
// stale (older than what was taken: reordered, late); the encoder frames then
// for an impossible count jump.
std::optional<double> MotorClient::FrameTime(SeqStampCheck* check, uint8_t seq, uint16_t stamp_ms,
                                             double now_s, std::optional<double>* last) {
  if (!check->Accept(seq, clock_.Peek(stamp_ms))) {
    ++counters_.implausible_time;
    return std::nullopt;
  }
  const auto t = ControllerTime(stamp_ms, now_s);
  if (!t) return std::nullopt;
  if (*last && *t <= **last) {
    ++(*t == **last ? counters_.duplicate : counters_.stale);
    return std::nullopt;
  }
  return t;
}

void MotorClient::HandleEncoder(const proto::EncoderCounts& e, double now_s, Event* ev) {
  ++counters_.encoder_frames;
  last_encoder_rx_ = now_s;  // the controller is there, whatever its data
  const auto t = FrameTime(&enc_check_, e.seq, e.timestamp_ms, now_s, &last_enc_t_);
  if (!t) return;
  if (options_.max_counts_per_s > 0 && last_enc_t_ && left_.initialized()) {
    const double limit = options_.max_counts_per_s * (*t - *last_enc_t_) + kCountSlack;
    const auto jump = [&](const Unwrapper16& u, uint16_t raw) {
      return std::abs(static_cast<double>(u.Peek(raw) - u.value())) > limit;
    };
    if (jump(left_, e.left) || jump(right_, e.right)) {
      ++counters_.implausible_counts;
      // One bad frame is dropped; a jump that stays (kConfirm in a row) is a
      // glitch of the counter itself: carry on from the new count.
      if (++count_suspects_ < kConfirm) return;
      left_.Rebase(left_.value());
      right_.Rebase(right_.value());
    }
  }
  count_suspects_ = 0;
  CheckSeq(&seq_encoder_, e.seq, &counters_.seq_gap_encoder);
  last_enc_t_ = t;
  ev->ticks = WheelTicks{*t, left_.Update(e.left), right_.Update(e.right)};
}

void MotorClient::HandleIrA(const proto::IrA& a, double now_s) {
  if (pending_ir_a_ && pending_ir_a_->seq == a.seq &&
      pending_ir_a_->timestamp_ms == a.timestamp_ms) {
    ++counters_.duplicate;
    return;
  }
  if (pending_ir_a_) ++counters_.ir_unpaired;
  pending_ir_a_.reset();
  if (FrameTime(&ir_check_, a.seq, a.timestamp_ms, now_s, &last_ir_t_)) pending_ir_a_ = a;
}

void MotorClient::HandleIrB(const proto::IrB& b, Event* ev) {
  if (!pending_ir_a_ && last_ir_pair_seq_ == b.seq) {
    ++counters_.duplicate;  // the B half of a sample already taken
    return;
  }
  if (!pending_ir_a_ || pending_ir_a_->seq != b.seq) {
    ++counters_.ir_unpaired;
    if (pending_ir_a_) ++counters_.ir_unpaired;
    pending_ir_a_.reset();
    return;
  }
  CheckSeq(&seq_ir_, b.seq, &counters_.seq_gap_ir);
  std::array<uint16_t, kNumIrSensors> adc{};
  for (int i = 0; i < 3; ++i) adc[i] = pending_ir_a_->adc[i];
  for (int i = 0; i < 4; ++i) adc[3 + i] = b.adc[i];
  ev->ir_t = static_cast<double>(clock_.Peek(pending_ir_a_->timestamp_ms)) * 1e-3;
  last_ir_t_ = ev->ir_t;
  last_ir_pair_seq_ = b.seq;
  ev->ir_adc = adc;
  pending_ir_a_.reset();
  ++counters_.ir_samples;
}

void MotorClient::HandleStatus(const proto::ControllerStatus& s, double now_s, Event* ev) {
  ++counters_.status_frames;
  last_status_rx_ = now_s;
  if (!FrameTime(&status_check_, s.seq, s.timestamp_ms, now_s, &last_status_t_)) return;
  CheckSeq(&seq_status_, s.seq, &counters_.seq_gap_status);
  last_status_ = s;
  ConfirmBumpers(s.bumpers);
  ev->status = s;
  ev->bumpers = bumpers_;
}

can_frame MotorClient::MakeCommand(const WheelCommand& cmd) {
  proto::WheelCmd m;
  m.left_mps = cmd.enable ? cmd.left_mps : 0.0;
  m.right_mps = cmd.enable ? cmd.right_mps : 0.0;
  m.enable = cmd.enable;
  m.seq = cmd_seq_++;
  return proto::Encode(m);
}

can_frame MotorClient::MakeHeartbeat(uint8_t daemon_state) {
  return proto::Encode(proto::DaemonHeartbeat{daemon_state, hb_seq_++});
}

const char* MotorClient::LossReason(double now_s) const {
  if (now_s - last_encoder_rx_ > options_.timeout_s) return "encoder frames timed out";
  // Status comes at 20 Hz: allow it a longer silence than encoder frames.
  if (now_s - last_status_rx_ > std::max(options_.timeout_s, 0.25)) {
    return "controller heartbeat timed out";
  }
  return "";
}

bool MotorClient::ControllerAlive(double now_s) const { return *LossReason(now_s) == '\0'; }

options::Table<MotorClientOptions> MotorClientKeys() {
  using M = MotorClientOptions;
  static constexpr options::Key<M> kKeys[] = {
      {"timeout_s", &M::timeout_s, 0.005, 10, "s", "encoder silence beyond this (robot time): fault"},
      {"plausible_speed_factor", &M::plausible_speed_factor, 0, 100, "",
       "count jumps faster than this x max_wheel_speed_mps are dropped (0 = off)"},
  };
  return kKeys;
}

}  // namespace irslam::drivers
