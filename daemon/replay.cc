#include "daemon/replay.h"

#include <algorithm>
#include <cmath>

#include "proto/codec.h"

namespace irslam {

Replay::Replay(robot::CoreOptions core, int64_t origin_ns, double time_scale)
    : core_(std::move(core)), origin_ns_(origin_ns), time_scale_(time_scale) {}

bool Replay::Driving(control::MissionState s) {
  return s != control::MissionState::kIdle && s != control::MissionState::kDone &&
         s != control::MissionState::kFault;
}

void Replay::Feed(const LogLine& line) {
  if (line.kind != LogLine::Kind::kFrame) {
    if (line.kind == LogLine::Kind::kForeign) ++stats_.ignored;
    return;
  }
  const double t = RobotTimeFromLogNs(line.stamp_ns - origin_ns_, time_scale_);
  if (!any_) stats_.first_t = t;
  any_ = true;
  stats_.last_t = t;
  switch (line.frame.can_id) {
    case proto::kControllerStatusId:
    case proto::kEncoderId:
    case proto::kIrAId:
    case proto::kIrBId:
      if (line.stamp_ns < skip_before_ns_) {
        ++stats_.skipped;
        break;
      }
      ++stats_.frames;
      core_.OnFrame(line.frame, t);
      break;
    case proto::kWheelCmdId: OnWheelCmd(line.frame, t); break;
    case proto::kDaemonHeartbeatId: OnHeartbeat(line.frame, t); break;
    default: ++stats_.ignored; break;
  }
}

void Replay::OnEvent(const LogEvent& event) {
  noted_ = true;
  const double t = RobotTimeFromLogNs(event.stamp_ns - origin_ns_, time_scale_);
  if (event.name == "start" || event.name == "start_clean") {
    // As irslamd's start: the mode applies unless a mission is running.
    const control::MissionState st = core_.state();
    if (st == control::MissionState::kIdle || st == control::MissionState::kDone ||
        st == control::MissionState::kFault) {
      core_.SetCleanMode(event.name == "start_clean");
    }
    StartMission(t);
  } else if (event.name == "stop") {
    core_.Stop(t);
    ++stats_.stops;
    stop_frame_next_ = true;
  }
}

void Replay::StartMission(double t) {
  std::string why;
  if (core_.Start(t, &why)) {
    ++stats_.starts;
    if (!stats_.started_t) stats_.started_t = t;
  } else if (stats_.start_error.empty()) {
    stats_.start_error = why;
  }
}

void Replay::OnWheelCmd(const can_frame& f, double t) {
  const proto::DecodeResult r = proto::Decode(f);
  const auto* cmd = r.ok() ? std::get_if<proto::WheelCmd>(&r.message) : nullptr;
  if (!cmd) {
    ++stats_.ignored;
    return;
  }
  if (!cmd->enable && stop_frame_next_) {
    // The noted stop call's immediate stop frame, between two ticks.
    stop_frame_next_ = false;
    ++stats_.stop_frames;
    return;
  }
  // (Not from a fault: the core leaves one by itself when the controller is back.)
  if (!noted_ && cmd->enable && !Driving(core_.state()) && core_.state() != control::MissionState::kFault) {
    StartMission(t);
  }
  const std::vector<can_frame> out = core_.Tick(t);
  ++stats_.ticks;
  // Enable the same and each velocity within one step of the encoding (1 mm/s): the
  // log's stamps carry the tick times to the microsecond, which may move a velocity
  // across a rounding boundary.
  const proto::DecodeResult mine = out.empty() ? proto::DecodeResult{} : proto::Decode(out[0]);
  const auto* own = mine.ok() ? std::get_if<proto::WheelCmd>(&mine.message) : nullptr;
  if (own && own->enable == cmd->enable && std::abs(own->left_mps - cmd->left_mps) < 0.0015 &&
      std::abs(own->right_mps - cmd->right_mps) < 0.0015) {
    ++stats_.commands_matched;
  } else {
    ++stats_.commands_differed;
  }
}

void Replay::OnHeartbeat(const can_frame& f, double t) {
  const proto::DecodeResult r = proto::Decode(f);
  const auto* hb = r.ok() ? std::get_if<proto::DaemonHeartbeat>(&r.message) : nullptr;
  if (!hb) {
    ++stats_.ignored;
    return;
  }
  ++stats_.heartbeats;
  const auto recorded = static_cast<control::MissionState>(hb->state);
  if (noted_) {
    // Start and stop are in the log: nothing to derive.
  } else if (Driving(recorded) && !Driving(core_.state()) && core_.state() != control::MissionState::kFault) {
    StartMission(t);
  } else if (recorded == control::MissionState::kIdle && Driving(core_.state())) {
    core_.Stop(t);
    ++stats_.stops;
  }
  if (recorded != core_.state()) ++stats_.states_differed;
}

void ControllerClockFit::Add(int64_t log_ns, uint16_t stamp_ms) {
  constexpr uint16_t kMaxStepMs = 1000;
  const auto step = static_cast<uint16_t>(stamp_ms - last_ms_);  // modulo 2^16
  if (n_ > 0 && step > kMaxStepMs) CloseSegment();
  if (n_ == 0) {
    first_ns_ = log_ns;
    robot_s_ = 0;
  } else {
    robot_s_ += 1e-3 * step;
  }
  last_ms_ = stamp_ms;
  const double x = robot_s_, y = 1e-9 * static_cast<double>(log_ns - first_ns_);
  sx_ += x;
  sy_ += y;
  sxx_ += x * x;
  sxy_ += x * y;
  ++n_;
  ++frames_;
}

void ControllerClockFit::AddOpenSegment(double* cxx, double* cxy, double* span) const {
  if (n_ < 2) return;
  const double n = static_cast<double>(n_);
  *cxx += sxx_ - sx_ * sx_ / n;
  *cxy += sxy_ - sx_ * sy_ / n;
  *span += robot_s_;
}

void ControllerClockFit::CloseSegment() {
  AddOpenSegment(&cxx_, &cxy_, &span_s_);
  sx_ = sy_ = sxx_ = sxy_ = 0;
  n_ = 0;
}

std::optional<double> ControllerClockFit::Scale() const {
  const auto k = Measured();
  return k ? std::optional<double>(RoundTimeScale(*k)) : std::nullopt;
}

std::optional<double> ControllerClockFit::Measured() const {
  double cxx = cxx_, cxy = cxy_, span = span_s_;
  AddOpenSegment(&cxx, &cxy, &span);
  // cxy / cxx: log seconds per robot second.
  if (frames_ < 100 || span < 1.0 || cxx <= 0 || cxy <= 0) return std::nullopt;
  return cxx / cxy;
}

double RoundTimeScale(double k) {
  const double mag1 = std::pow(10.0, std::floor(std::log10(k)));
  const double one = std::round(k / mag1) * mag1;
  if (std::abs(one - k) <= 0.03 * k) return one;
  const double mag2 = mag1 / 10;
  return std::round(k / mag2) * mag2;
}

std::optional<double> EstimateTimeScale(const std::vector<int64_t>& stamps_ns, double period_s) {
  // The control period is timed on an absolute clock: each command is a whole number
  // of periods after the one before, plus the difference of two wake-up latencies. A
  // loaded machine skips periods (the daemon runs one tick per wake-up), so a median
  // spacing, even over windows, can be a period and a bit.
  //  1. p1: the mean of the spacings under 1.5 median spacings (most are one period;
  //     a run of them sums to its periods plus the latencies of its two ends).
  //  2. Over windows of 10 spacings (the latencies of the two ends only), the whole
  //     number of periods n = round(window / p1), counting the skipped ones; the
  //     period is the median of window / n.
  constexpr size_t kWindow = 10;
  if (stamps_ns.size() < kWindow + 1) return std::nullopt;
  std::vector<double> d;
  for (size_t i = 1; i < stamps_ns.size(); ++i) {
    if (stamps_ns[i] > stamps_ns[i - 1]) d.push_back(static_cast<double>(stamps_ns[i] - stamps_ns[i - 1]) * 1e-9);
  }
  if (d.size() < kWindow) return std::nullopt;
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  const double p_med = median(d);
  double sum = 0;
  int count = 0;
  for (double x : d) {
    if (x < 1.5 * p_med) {
      sum += x;
      ++count;
    }
  }
  const double p1 = sum / count;  // p_med itself is counted
  std::vector<double> per;
  for (size_t i = kWindow; i < stamps_ns.size(); ++i) {
    const double w = static_cast<double>(stamps_ns[i] - stamps_ns[i - kWindow]) * 1e-9;
    const double n = std::round(w / p1);
    if (n >= 1) per.push_back(w / n);
  }
  if (per.empty()) return std::nullopt;
  return RoundTimeScale(period_s / median(per));
}

}  // namespace irslam
