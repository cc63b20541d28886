// status (contracts.md §6): the core's status with the daemon's own parts (loop
// period statistics, CAN, API, GPIO, the map store, notification) added. The one
// place that calls RobotCore::Status for the API.
#include "daemon/irslamd.h"

namespace irslam {
namespace {

nlohmann::json CanJson(const drivers::CanBus& bus) {
  const auto& c = bus.stats();
  return {{"iface", bus.name()},         {"rx", c.rx_frames},
          {"tx", c.tx_frames},           {"rx_dropped", c.rx_dropped},
          {"tx_dropped", c.tx_dropped},  {"filtered", c.filtered},
          {"error_frames", c.error_frames}, {"bus_off", c.bus_off},
          {"link_up", c.link_up},        {"link_down_events", c.link_down_events},
          {"last_error", c.last_error},  {"last_rx_time", c.last_rx_time},
          {"kernel_timestamps", c.kernel_timestamps}};
}

nlohmann::json GpioJson(const drivers::Gpio& gpio) {
  nlohmann::json lines = nlohmann::json::object();
  for (const auto& l : gpio.lines()) {
    lines[l.role] = {{"chip", l.chip},     {"label", l.label},   {"offset", l.offset},
                     {"name", l.name},     {"output", l.output}, {"active", l.active}};
  }
  return {{"lines", lines}, {"events", gpio.events()}};
}

}  // namespace

// The per-period work (issue 15), seconds: quantiles of the fixed-bucket
// histogram (a bucket's upper edge, at most 12.5 % high), the maximum per
// phase, and the worst period by phase.
static nlohmann::json TickProfileJson(const robot::TickProfile& p) {
  using robot::TickPhase;
  const auto& w = p.work();
  nlohmann::json phase_max = nlohmann::json::object(), worst = nlohmann::json::object();
  for (int i = 0; i < robot::kNumTickPhases; ++i) {
    const auto ph = static_cast<TickPhase>(i);
    phase_max[robot::ToString(ph)] = static_cast<double>(p.phase_max(ph)) * 1e-9;
    worst[robot::ToString(ph)] = static_cast<double>(p.worst()[ph]) * 1e-9;
  }
  worst["robot_time"] = p.worst_t();
  worst["phase"] = robot::ToString(p.worst_phase());
  return {{"p50", static_cast<double>(w.Quantile(0.5)) * 1e-9},
          {"p99", static_cast<double>(w.Quantile(0.99)) * 1e-9},
          {"p999", static_cast<double>(w.Quantile(0.999)) * 1e-9},
          {"max", static_cast<double>(w.max()) * 1e-9},
          {"mean", w.mean() * 1e-9},
          {"periods", w.count()},
          {"phase_max", phase_max},
          {"worst", worst}};
}

nlohmann::json Daemon::StatusJson() {
  const double now = RobotNow();
  nlohmann::json s = ToJson(core_->Status(now));
  s["uptime"] = WallNow();
  s["time_scale"] = options_.time_scale;
  s["period"] = {{"target", settings_.core.period_s},
                 {"ticks", scheduler_.ticks()},
                 {"overruns", scheduler_.overruns()},
                 {"jitter_mean", scheduler_.mean_late_ns() * 1e-9},
                 {"jitter_max", static_cast<double>(scheduler_.max_late_ns()) * 1e-9},
                 {"jitter_last", static_cast<double>(scheduler_.last_late_ns()) * 1e-9},
                 {"work_max", max_work_s_},
                 {"work", TickProfileJson(profile_)},
                 {"loop_stalls", core_->loop_stalls()},
                 {"scheduling", scheduling_.Describe(settings_.realtime_priority)},
                 {"api_scheduling", api_scheduling_.Describe(ApiThreadPriority(settings_.realtime_priority))}};
  const auto& ps = core_->planner_stats();
  s["period"]["planner"] = {{"plans", ps.plans},       {"searches", ps.searches},
                            {"failed", ps.failed},     {"known_unreachable", ps.known_unreachable},
                            {"pops", ps.pops},         {"max_pops", ps.max_pops}};
  if (bus_) {
    s["can"] = CanJson(*bus_);
    foreign_.AddStatus(WallNow(), &s["can"]);
  }
  if (api_) s["api"] = api_->StatsJson();
  s["config_pending"] = pending_options_.has_value();
  s["notify_dropped"] = notifier_.dropped();
  if (gpio_) s["gpio"] = GpioJson(*gpio_);
  s["map_store"] = maps_.StatusJson();
  if (recorder_) {
    const RecorderStats r = recorder_->stats();
    s["record"] = {{"path", r.path},          {"lines", r.lines},         {"dropped", r.dropped},
                   {"bytes", r.bytes},        {"rotations", r.rotations}, {"error", r.error}};
  }
  return s;
}

}  // namespace irslam
