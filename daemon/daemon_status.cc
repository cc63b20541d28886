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

nlohmann::json Daemon::StatusJson() {
  const double now = RobotNow();
  nlohmann::json s = ToJson(core_->Status(now));
  s["uptime"] = WallNow();
  s["time_scale"] = options_.time_scale;
  s["period"] = {{"target", core_options_.period_s},
                 {"ticks", scheduler_.ticks()},
                 {"overruns", scheduler_.overruns()},
                 {"jitter_mean", scheduler_.mean_late_ns() * 1e-9},
                 {"jitter_max", static_cast<double>(scheduler_.max_late_ns()) * 1e-9},
                 {"jitter_last", static_cast<double>(scheduler_.last_late_ns()) * 1e-9},
                 {"work_max", max_work_s_}};
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
