#include "drivers/motor_client.h"

#include <algorithm>

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

double MotorClient::ControllerTime(uint16_t stamp_ms) {
  const int64_t before = clock_.value();
  const bool had = clock_.initialized();
  int64_t now = clock_.Update(stamp_ms);
  // A controller clock that jumps back by more than a second has been reset:
  // keep our time base continuous and restart the wheel count bases.
  if (had && now < before - 1000) {
    ++counters_.controller_resets;
    clock_.Rebase(before + 10);
    now = clock_.Update(stamp_ms);
    left_.Rebase(left_.value());
    right_.Rebase(right_.value());
    seq_encoder_.reset();
    seq_ir_.reset();
    seq_status_.reset();
    pending_ir_a_.reset();
  }
  return static_cast<double>(now) * 1e-3;
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
    ++counters_.encoder_frames;
    const double t = ControllerTime(e->timestamp_ms);
    CheckSeq(&seq_encoder_, e->seq, &counters_.seq_gap_encoder);
    ev.ticks = WheelTicks{t, left_.Update(e->left), right_.Update(e->right)};
    last_encoder_rx_ = now_s;
  } else if (const auto* a = std::get_if<proto::IrA>(&r.message)) {
    if (pending_ir_a_) ++counters_.ir_unpaired;
    pending_ir_a_ = *a;
  } else if (const auto* b = std::get_if<proto::IrB>(&r.message)) {
    if (!pending_ir_a_ || pending_ir_a_->seq != b->seq) {
      ++counters_.ir_unpaired;
      if (pending_ir_a_) ++counters_.ir_unpaired;
      pending_ir_a_.reset();
      return ev;
    }
    CheckSeq(&seq_ir_, b->seq, &counters_.seq_gap_ir);
    std::array<uint16_t, kNumIrSensors> adc{};
    for (int i = 0; i < 3; ++i) adc[i] = pending_ir_a_->adc[i];
    for (int i = 0; i < 4; ++i) adc[3 + i] = b->adc[i];
    ev.ir_t = ControllerTime(pending_ir_a_->timestamp_ms);
    ev.ir_adc = adc;
    pending_ir_a_.reset();
    ++counters_.ir_samples;
  } else if (const auto* s = std::get_if<proto::ControllerStatus>(&r.message)) {
    ++counters_.status_frames;
    ControllerTime(s->timestamp_ms);
    CheckSeq(&seq_status_, s->seq, &counters_.seq_gap_status);
    last_status_ = *s;
    ev.status = *s;
    last_status_rx_ = now_s;
  } else {
    ++counters_.ignored;
  }
  return ev;
}

can_frame MotorClient::MakeCommand(const WheelCommand& cmd) {
  proto::WheelCommand m;
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

}  // namespace irslam::drivers
