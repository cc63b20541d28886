#include "daemon/core_json.h"

namespace irslam {
namespace {

using nlohmann::json;

json PoseJson(const Pose2& p) { return {p.x, p.y, p.theta}; }

json MatrixJson(const Eigen::MatrixXd& m) {
  json rows = json::array();
  for (int i = 0; i < m.rows(); ++i) {
    json row = json::array();
    for (int j = 0; j < m.cols(); ++j) row.push_back(m(i, j));
    rows.push_back(row);
  }
  return rows;
}

json BoxJson(const control::Box& b) { return json{b.xmin, b.ymin, b.xmax, b.ymax}; }

json SlamStatsJson(const slam::SlamStats& st) {
  return {{"windows", st.windows},           {"lines_extracted", st.lines_extracted},
          {"updates", st.updates},           {"insertions", st.insertions},
          {"rejected_angle", st.rejected_angle}, {"merges", st.merges},
          {"loop_closures", st.loop_closures}, {"rejected_gate", st.rejected_gate},
          {"gate_recoveries", st.gate_recoveries}};
}

json SafetyJson(const robot::SafetyStatus& s) {
  return {{"estop", s.estop},
          {"estop_latched", s.estop_latched},
          {"bumper_left", s.bumper_left},
          {"bumper_right", s.bumper_right},
          {"motor_enable", s.motor_enable}};
}

json ControllerJson(const robot::ControllerLink& c) {
  const auto& st = c.last;
  return {{"alive", c.alive},
          {"state", st ? static_cast<int>(st->state) : -1},
          {"faults", st ? st->faults : 0},
          {"bumpers", st ? st->bumpers : 0},
          {"battery", st ? st->battery_v : 0.0}};
}

json FramesJson(const robot::FrameCounters& f) {
  const drivers::MotorClientCounters& c = f.motor;
  return {{"encoder", c.encoder_frames},
          {"ir", c.ir_samples},
          {"status", c.status_frames},
          {"unknown_id", c.unknown_id},
          {"wrong_dlc", c.wrong_dlc},
          {"ignored", c.ignored},
          {"seq_gap_encoder", c.seq_gap_encoder},
          {"seq_gap_ir", c.seq_gap_ir},
          {"seq_gap_status", c.seq_gap_status},
          {"ir_unpaired", c.ir_unpaired},
          {"controller_resets", c.controller_resets},
          {"clock_jumps", c.clock_jumps},
          {"duplicate", c.duplicate},
          {"stale", c.stale},
          {"implausible_time", c.implausible_time},
          {"implausible_counts", c.implausible_counts},
          {"ir_out_of_range", f.ir.out_of_range},
          {"ir_stuck", f.ir.stuck},
          {"bumper_unconfirmed", c.bumper_unconfirmed}};
}

json RoomJson(const control::RoomModel& room) {
  return {{"walls",
           {{"bottom", room.walls[0]}, {"right", room.walls[1]}, {"top", room.walls[2]}, {"left", room.walls[3]}}},
          {"box", room.box ? BoxJson(*room.box) : json()}};
}

json ObjectJson(const control::ObjectModel& o) {
  json j = {{"id", o.id},         {"kind", ToString(o.kind)},  {"lines", o.lines},
            {"complete", o.complete}, {"box", BoxJson(o.box)}, {"open_ends", o.open_ends}};
  if (!o.note.empty()) j["note"] = o.note;
  return j;
}

json LineJson(const slam::LineFeature& l) {
  return {{"id", l.id},
          {"rho", l.rho},
          {"theta", l.theta},
          {"cov", MatrixJson(l.cov)},
          {"p0", {l.p0.x(), l.p0.y()}},
          {"p1", {l.p1.x(), l.p1.y()}},
          {"length", l.length()},
          {"observations", l.observations}};
}

json PointsJson(const std::vector<Eigen::Vector2d>& pts) {
  json a = json::array();
  for (const auto& p : pts) a.push_back({p.x(), p.y()});
  return a;
}

// contracts §7: status.cleaning (without cells) and the map's "cleaning" (with them).
json CleaningJson(const control::CleaningProgress& c, bool cells) {
  json j = {{"state", ToString(c.state)},
            {"started_t", c.started_t},
            {"finished_t", c.finished_t > 0 ? json(c.finished_t) : json()},
            {"swept_t", c.swept_t > 0 ? json(c.swept_t) : json()},
            {"cells_done", c.cells_done},
            {"cells_total", c.cells_total},
            {"covered_m2", c.covered_m2},
            {"total_m2", c.total_m2},
            {"fraction", c.fraction},
            {"path_m", c.path_m},
            {"eta_s", c.eta_s},
            {"unreachable_m2", c.unreachable_m2},
            {"cross_track_rms_m", c.cross_track_rms_m},
            {"cross_track_max_m", c.cross_track_max_m},
            {"width_m", c.cleaning_width_m}};
  if (cells) {
    json a = json::array();
    for (const auto& cell : c.cells) {
      a.push_back({{"id", cell.id},
                   {"polygon", PointsJson(cell.polygon)},
                   {"route", PointsJson(cell.route)},
                   {"done", cell.done},
                   {"unreachable", cell.unreachable}});
    }
    j["cells"] = a;
  }
  return j;
}

}  // namespace

json CalibrationJson(const slam::CalibrationEstimate& c) {
  return {{"scale", {c.value.left, c.value.right, c.value.base}},
          {"std", {c.sigma(0), c.sigma(1), c.sigma(2)}},
          {"ratio", c.value.ratio()},
          {"ratio_std", c.ratio_sigma}};
}

std::optional<slam::CalibrationEstimate> CalibrationFromMap(const json& map) {
  if (!map.is_object() || !map.contains("calibration")) return std::nullopt;
  const json& c = map["calibration"];
  const auto numbers = [&](const char* key, double lo, double hi, double out[3]) {
    if (!c.is_object() || !c.contains(key) || !c[key].is_array() || c[key].size() != 3) return false;
    for (size_t i = 0; i < 3; ++i) {
      if (!c[key][i].is_number()) return false;
      out[i] = c[key][i].get<double>();
      if (!(out[i] >= lo && out[i] <= hi)) return false;
    }
    return true;
  };
  double scale[3], sd[3];
  if (!numbers("scale", 0.5, 1.5, scale) || !numbers("std", 0, 0.5, sd)) return std::nullopt;
  slam::CalibrationEstimate e;
  e.value = {scale[0], scale[1], scale[2]};
  e.sigma = Eigen::Vector3d(sd[0], sd[1], sd[2]);
  e.ratio_sigma = c.contains("ratio_std") && c["ratio_std"].is_number() ? c["ratio_std"].get<double>() : 0.0;
  return e;
}

json ToJson(const robot::CoreStatus& s) {
  json slam = SlamStatsJson(s.slam.stats);
  slam["calibration"] = CalibrationJson(s.slam.calibration);
  slam["calibration"]["enabled"] = s.slam.calibration_enabled;
  json ranges = json::array();
  for (const auto& r : s.ir.scan.range_m) ranges.push_back(r ? json(*r) : json());
  json j = {
      {"state", ToString(s.mission.state)},
      {"reason", s.mission.reason},
      {"behaviour", ToString(s.mission.behaviour)},
      {"robot_time", s.robot_time},
      {"pose", PoseJson(s.slam.pose)},
      {"pose_std", s.slam.pose_std},
      {"distance", s.slam.distance_m},
      {"lines", s.slam.lines},
      {"slam", slam},
      {"objects", s.model.objects},
      {"objects_pending", s.model.pending},
      {"target_object", s.mission.target_object},
      {"ir_ranges", ranges},
      {"ir_adc", s.ir.adc},
      {"command", {s.command.left_mps, s.command.right_mps}},
      {"safety", SafetyJson(s.safety)},
      {"controller", ControllerJson(s.controller)},
      {"frames", FramesJson(s.frames)},
  };
  if (s.cleaning) j["cleaning"] = CleaningJson(*s.cleaning, false);
  return j;
}

json ToJson(const robot::MapSnapshot& m) {
  json objects = json::array();
  for (const auto& o : m.objects) objects.push_back(ObjectJson(o));
  json lines = json::array();
  for (const auto& l : m.lines) lines.push_back(LineJson(l));
  json traj = json::array();
  for (const auto& p : m.trajectory) traj.push_back({p.t, p.pose.x, p.pose.y, p.pose.theta});
  json j = {
      {"frame", "map"},
      {"state", ToString(m.state)},
      {"pose", PoseJson(m.pose)},
      {"pose_cov", MatrixJson(m.pose_cov)},
      {"lines", lines},
      {"room", RoomJson(m.room)},
      {"objects", objects},
      {"trajectory", traj},
  };
  if (m.cleaning) j["cleaning"] = CleaningJson(*m.cleaning, true);
  if (m.calibration) j["calibration"] = CalibrationJson(*m.calibration);
  return j;
}

}  // namespace irslam
