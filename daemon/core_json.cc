// The JSON views of the core's status and map (daemon/core_json.h) and the
// map's reader, MapFromJson. Longer than the ~400-line bar (issue 10) on
// purpose: the reader (MapReader, its Read* functions and MapFromJson, ~340
// lines) is the writer's inverse field for field (ToJson(*map) == j for every
// map ToJson wrote), so the two sit in one file where a field added to one is
// seen missing in the other; each half alone is under the bar.
#include "daemon/core_json.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iterator>
#include <set>

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
          {"gate_recoveries", st.gate_recoveries}, {"fallback_matches", st.fallback_matches}};
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
  json j = {{"id", l.id},
            {"rho", l.rho},
            {"theta", l.theta},
            {"cov", MatrixJson(l.cov)},
            {"p0", {l.p0.x(), l.p0.y()}},
            {"p1", {l.p1.x(), l.p1.y()}},
            {"length", l.length()},
            {"observations", l.observations}};
  if (!l.merged.empty()) j["merged"] = l.merged;
  return j;
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
    if (c.planned) {
      json objects = json::array();
      for (const auto& b : c.planned->objects) objects.push_back(BoxJson(b));
      j["planned"] = {{"room", BoxJson(c.planned->room)},
                      {"objects", std::move(objects)},
                      {"contacts", PointsJson(c.planned->contacts)}};
    }
  }
  return j;
}

// contracts §7: status.relocalize (issue 14).
json RelocalizeJson(const robot::RelocalizeStatus& r) {
  const auto finite = [](double x) { return std::isfinite(x) ? json(x) : json(); };
  return {{"committed", r.committed},
          {"started_t", r.started_t},
          {"committed_t", r.committed ? json(r.committed_t) : json()},
          {"hypotheses", r.hypotheses},
          {"best_score", finite(r.best_score)},
          {"evidence_m", r.evidence_m},
          {"attempts", r.attempts}};
}

// MapFromJson's reader: each getter checks one value, records the first failure
// as "map.<where>: <what>" and returns false; later calls then do nothing.
class MapReader {
 public:
  explicit MapReader(std::string* why) : why_(why) {}
  bool ok() const { return ok_; }
  bool Fail(const std::string& at, const std::string& what) {
    if (ok_) {
      ok_ = false;
      *why_ = "map" + (at.empty() ? std::string() : "." + at) + ": " + what;
    }
    return false;
  }
  // The member `key` of object j, or nullptr (a failure when required).
  const json* Member(const json& j, const std::string& at, const char* key, bool required) {
    if (!ok_) return nullptr;
    const auto it = j.find(key);
    if (it == j.end()) {
      if (required) Fail(Join(at, key), "missing");
      return nullptr;
    }
    return &*it;
  }
  bool Number(const json& j, const std::string& at, double* out, double bound = kMaxMapCoordM) {
    if (!ok_) return false;
    if (!j.is_number()) return Fail(at, "not a number");
    *out = j.get<double>();
    if (!std::isfinite(*out) || std::abs(*out) > bound) return Fail(at, "not a finite number within ±" + Bound(bound));
    return true;
  }
  bool Int(const json& j, const std::string& at, int* out, int64_t lo, int64_t hi) {
    if (!ok_) return false;
    if (!j.is_number_integer()) return Fail(at, "not an integer");
    const bool too_big = j.is_number_unsigned() && j.get<uint64_t>() > static_cast<uint64_t>(hi);
    const int64_t v = too_big ? hi : j.get<int64_t>();
    if (too_big || v < lo || v > hi)
      return Fail(at, "out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    *out = static_cast<int>(v);
    return true;
  }
  bool Bool(const json& j, const std::string& at, bool* out) {
    if (!ok_) return false;
    if (!j.is_boolean()) return Fail(at, "not a boolean");
    *out = j.get<bool>();
    return true;
  }
  bool String(const json& j, const std::string& at, std::string* out, size_t max = 4096) {
    if (!ok_) return false;
    if (!j.is_string()) return Fail(at, "not a string");
    if (j.get_ref<const std::string&>().size() > max) return Fail(at, "longer than " + std::to_string(max) + " characters");
    *out = j.get<std::string>();
    return true;
  }
  bool Array(const json& j, const std::string& at, size_t max) {
    if (!ok_) return false;
    if (!j.is_array()) return Fail(at, "not an array");
    if (j.size() > max) return Fail(at, "more than " + std::to_string(max) + " entries");
    return true;
  }
  bool Object(const json& j, const std::string& at) {
    if (!ok_) return false;
    if (!j.is_object()) return Fail(at, "not an object");
    return true;
  }
  // An array of exactly n finite numbers.
  bool Numbers(const json& j, const std::string& at, size_t n, double* out, double bound = kMaxMapCoordM) {
    if (!ok_) return false;
    if (!j.is_array() || j.size() != n) return Fail(at, "not an array of " + std::to_string(n) + " numbers");
    for (size_t i = 0; i < n; ++i) {
      if (!Number(j[i], at + "[" + std::to_string(i) + "]", &out[i], bound)) return false;
    }
    return true;
  }
  template <int N>
  bool Matrix(const json& j, const std::string& at, Eigen::Matrix<double, N, N>* m) {
    if (!ok_) return false;
    const std::string what = "not a " + std::to_string(N) + "x" + std::to_string(N) + " matrix of numbers";
    if (!j.is_array() || j.size() != N) return Fail(at, what);
    for (int r = 0; r < N; ++r) {
      if (!j[r].is_array() || j[r].size() != N) return Fail(at, what);
      for (int c = 0; c < N; ++c) {
        if (!Number(j[r][c], at + "[" + std::to_string(r) + "][" + std::to_string(c) + "]", &(*m)(r, c), 1e6))
          return false;
      }
    }
    return true;
  }
  bool Point(const json& j, const std::string& at, Eigen::Vector2d* p) {
    double v[2];
    if (!Numbers(j, at, 2, v)) return false;
    *p = {v[0], v[1]};
    return true;
  }
  bool Points(const json& j, const std::string& at, std::vector<Eigen::Vector2d>* out) {
    if (!Array(j, at, kMaxMapPolygon)) return false;
    out->resize(j.size());
    for (size_t i = 0; i < j.size(); ++i) {
      if (!Point(j[i], at + "[" + std::to_string(i) + "]", &(*out)[i])) return false;
    }
    return true;
  }
  bool Box(const json& j, const std::string& at, control::Box* b) {
    double v[4];
    if (!Numbers(j, at, 4, v)) return false;
    *b = {v[0], v[1], v[2], v[3]};
    return true;
  }
  // Line ids (of a wall or an object's sides). Ids that name no line of the map
  // are kept: real maps have them (the model is made at the model step, and the
  // SLAM merges lines after it), so readers must skip them.
  bool Ids(const json& j, const std::string& at, std::vector<int>* out) {
    if (!Array(j, at, kMaxMapLines)) return false;
    out->resize(j.size());
    for (size_t i = 0; i < j.size(); ++i) {
      if (!Int(j[i], at + "[" + std::to_string(i) + "]", &(*out)[i], 0, INT32_MAX)) return false;
    }
    return true;
  }
  // An enum from its ToString name (tries every value of the underlying type).
  template <typename E>
  bool Enum(const json& j, const std::string& at, E* out) {
    std::string name;
    if (!String(j, at, &name, 64)) return false;
    for (int v = 0; v < 256; ++v) {
      const char* s = ToString(static_cast<E>(v));
      if (name == s && std::string(s) != "?") {
        *out = static_cast<E>(v);
        return true;
      }
    }
    return Fail(at, "unknown value \"" + name + "\"");
  }
  static std::string Join(const std::string& at, const char* key) { return at.empty() ? key : at + "." + key; }

 private:
  static std::string Bound(double b) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", b);
    return buf;
  }
  std::string* why_;
  bool ok_ = true;
};

// A number that ToJson writes as null when 0 (finished_t, swept_t).
bool ZeroOrNumber(MapReader* r, const json& j, const std::string& at, double* out) {
  if (j.is_null()) {
    *out = 0;
    return true;
  }
  return r->Number(j, at, out, 1e9);
}

bool ReadLine(MapReader* r, const json& j, const std::string& at, slam::LineFeature* l) {
  if (!r->Object(j, at)) return false;
  const json* v;
  if ((v = r->Member(j, at, "id", true))) r->Int(*v, at + ".id", &l->id, 0, INT32_MAX);
  if ((v = r->Member(j, at, "rho", true))) r->Number(*v, at + ".rho", &l->rho);
  if ((v = r->Member(j, at, "theta", true))) r->Number(*v, at + ".theta", &l->theta, 2 * M_PI);
  if ((v = r->Member(j, at, "cov", true))) r->Matrix<2>(*v, at + ".cov", &l->cov);
  if ((v = r->Member(j, at, "p0", true))) r->Point(*v, at + ".p0", &l->p0);
  if ((v = r->Member(j, at, "p1", true))) r->Point(*v, at + ".p1", &l->p1);
  if ((v = r->Member(j, at, "observations", false))) r->Int(*v, at + ".observations", &l->observations, 0, INT32_MAX);
  if ((v = r->Member(j, at, "merged", false))) r->Ids(*v, at + ".merged", &l->merged);
  double length;
  if ((v = r->Member(j, at, "length", false))) r->Number(*v, at + ".length", &length, 1e6);
  return r->ok();
}

bool ReadObject(MapReader* r, const json& j, const std::string& at, control::ObjectModel* o) {
  if (!r->Object(j, at)) return false;
  const json* v;
  if ((v = r->Member(j, at, "id", true))) r->Int(*v, at + ".id", &o->id, 0, INT32_MAX);
  if ((v = r->Member(j, at, "kind", true))) {
    std::string kind;
    if (r->String(*v, at + ".kind", &kind, 64)) {
      if (kind == ToString(control::ObjectKind::kWallContact)) {
        o->kind = control::ObjectKind::kWallContact;
      } else if (kind == ToString(control::ObjectKind::kFree)) {
        o->kind = control::ObjectKind::kFree;
      } else {
        r->Fail(at + ".kind", "not \"wall_contact\" or \"free\"");
      }
    }
  }
  if ((v = r->Member(j, at, "lines", true))) r->Ids(*v, at + ".lines", &o->lines);
  if ((v = r->Member(j, at, "complete", false))) r->Bool(*v, at + ".complete", &o->complete);
  if ((v = r->Member(j, at, "box", false))) r->Box(*v, at + ".box", &o->box);
  if ((v = r->Member(j, at, "open_ends", false))) r->Int(*v, at + ".open_ends", &o->open_ends, 0, 1000000);
  if ((v = r->Member(j, at, "given_up", false))) r->Bool(*v, at + ".given_up", &o->given_up);
  if ((v = r->Member(j, at, "note", false))) r->String(*v, at + ".note", &o->note);
  return r->ok();
}

bool ReadRoom(MapReader* r, const json& j, control::RoomModel* room) {
  if (!r->Object(j, "room")) return false;
  if (const json* w = r->Member(j, "room", "walls", false); w && r->Object(*w, "room.walls")) {
    static constexpr const char* kSides[4] = {"bottom", "right", "top", "left"};
    for (const auto& item : w->items()) {
      if (std::find(std::begin(kSides), std::end(kSides), item.key()) == std::end(kSides))
        return r->Fail("room.walls." + item.key(), "not bottom, right, top or left");
    }
    for (int i = 0; i < 4; ++i) {
      if (const json* side = r->Member(*w, "room.walls", kSides[i], false))
        r->Ids(*side, std::string("room.walls.") + kSides[i], &room->walls[i]);
    }
  }
  if (const json* b = r->Member(j, "room", "box", false); b && !b->is_null()) {
    control::Box box;
    if (r->Box(*b, "room.box", &box)) room->box = box;
  }
  return r->ok();
}

bool ReadCleaning(MapReader* r, const json& j, control::CleaningProgress* c) {
  const std::string at = "cleaning";
  if (!r->Object(j, at)) return false;
  const json* v;
  if ((v = r->Member(j, at, "state", true))) r->Enum(*v, at + ".state", &c->state);
  const std::pair<const char*, double*> numbers[] = {
      {"started_t", &c->started_t},   {"covered_m2", &c->covered_m2},
      {"total_m2", &c->total_m2},     {"fraction", &c->fraction},
      {"path_m", &c->path_m},         {"eta_s", &c->eta_s},
      {"unreachable_m2", &c->unreachable_m2}, {"cross_track_rms_m", &c->cross_track_rms_m},
      {"cross_track_max_m", &c->cross_track_max_m}, {"width_m", &c->cleaning_width_m}};
  for (const auto& [key, out] : numbers) {
    if ((v = r->Member(j, at, key, false))) r->Number(*v, at + "." + key, out, 1e9);
  }
  if ((v = r->Member(j, at, "finished_t", false))) ZeroOrNumber(r, *v, at + ".finished_t", &c->finished_t);
  if ((v = r->Member(j, at, "swept_t", false))) ZeroOrNumber(r, *v, at + ".swept_t", &c->swept_t);
  if ((v = r->Member(j, at, "cells_done", false))) r->Int(*v, at + ".cells_done", &c->cells_done, 0, kMaxMapCells);
  if ((v = r->Member(j, at, "cells_total", false))) r->Int(*v, at + ".cells_total", &c->cells_total, 0, kMaxMapCells);
  if ((v = r->Member(j, at, "cells", false)) && r->Array(*v, at + ".cells", kMaxMapCells)) {
    c->cells.resize(v->size());
    for (size_t i = 0; i < v->size() && r->ok(); ++i) {
      const json& cj = (*v)[i];
      const std::string here = at + ".cells[" + std::to_string(i) + "]";
      control::CleaningProgress::Cell& cell = c->cells[i];
      if (!r->Object(cj, here)) break;
      const json* f;
      if ((f = r->Member(cj, here, "id", true))) r->Int(*f, here + ".id", &cell.id, 0, INT32_MAX);
      if ((f = r->Member(cj, here, "polygon", true))) r->Points(*f, here + ".polygon", &cell.polygon);
      if ((f = r->Member(cj, here, "route", true))) r->Points(*f, here + ".route", &cell.route);
      if ((f = r->Member(cj, here, "done", true))) r->Bool(*f, here + ".done", &cell.done);
      if ((f = r->Member(cj, here, "unreachable", false))) r->Bool(*f, here + ".unreachable", &cell.unreachable);
    }
  }
  if ((v = r->Member(j, at, "planned", false)) && r->Object(*v, at + ".planned")) {
    const std::string here = at + ".planned";
    control::CleaningProgress::PlanInputs in;
    const json* f;
    if ((f = r->Member(*v, here, "room", true))) r->Box(*f, here + ".room", &in.room);
    if ((f = r->Member(*v, here, "objects", true)) && r->Array(*f, here + ".objects", kMaxMapObjects)) {
      in.objects.resize(f->size());
      for (size_t i = 0; i < f->size() && r->ok(); ++i)
        r->Box((*f)[i], here + ".objects[" + std::to_string(i) + "]", &in.objects[i]);
    }
    if ((f = r->Member(*v, here, "contacts", true))) r->Points(*f, here + ".contacts", &in.contacts);
    if (r->ok()) c->planned = std::move(in);
  }
  return r->ok();
}

bool ReadCalibration(MapReader* r, const json& j, slam::CalibrationEstimate* e) {
  const std::string at = "calibration";
  if (!r->Object(j, at)) return false;
  double scale[3], sd[3];
  const json* v;
  if ((v = r->Member(j, at, "scale", true)) && r->Numbers(*v, at + ".scale", 3, scale)) {
    for (double s : scale) {
      if (!(s >= 0.5 && s <= 1.5)) return r->Fail(at + ".scale", "a scale factor outside [0.5, 1.5]");
    }
    e->value = {scale[0], scale[1], scale[2]};
  }
  if ((v = r->Member(j, at, "std", true)) && r->Numbers(*v, at + ".std", 3, sd)) {
    for (double s : sd) {
      if (!(s >= 0 && s <= 0.5)) return r->Fail(at + ".std", "a standard deviation outside [0, 0.5]");
    }
    e->sigma = Eigen::Vector3d(sd[0], sd[1], sd[2]);
  }
  double ratio;
  if ((v = r->Member(j, at, "ratio", false))) r->Number(*v, at + ".ratio", &ratio);
  e->ratio_sigma = 0;
  if ((v = r->Member(j, at, "ratio_std", false))) r->Number(*v, at + ".ratio_std", &e->ratio_sigma, 0.5);
  return r->ok();
}

}  // namespace

bool MapFromJson(const json& j, robot::MapSnapshot* map, std::string* why) {
  MapReader r(why);
  *map = robot::MapSnapshot();
  if (!r.Object(j, "")) return false;
  const json* v;
  if ((v = r.Member(j, "", "frame", true))) {
    std::string frame;
    if (r.String(*v, "frame", &frame, 64) && frame != "map") r.Fail("frame", "not \"map\"");
  }
  if ((v = r.Member(j, "", "state", true))) r.Enum(*v, "state", &map->state);
  if ((v = r.Member(j, "", "pose", false))) {
    double p[3];
    if (r.Numbers(*v, "pose", 3, p)) map->pose = {p[0], p[1], p[2]};
  }
  if ((v = r.Member(j, "", "pose_cov", false))) {
    Eigen::Matrix3d m;
    if (r.Matrix<3>(*v, "pose_cov", &m)) map->pose_cov = m;
  }
  std::set<int> ids;
  if ((v = r.Member(j, "", "lines", true)) && r.Array(*v, "lines", kMaxMapLines)) {
    map->lines.resize(v->size());
    for (size_t i = 0; i < v->size() && r.ok(); ++i) {
      const std::string at = "lines[" + std::to_string(i) + "]";
      if (ReadLine(&r, (*v)[i], at, &map->lines[i]) && !ids.insert(map->lines[i].id).second)
        r.Fail(at + ".id", "line " + std::to_string(map->lines[i].id) + " is in the map twice");
    }
  }
  if ((v = r.Member(j, "", "room", false))) ReadRoom(&r, *v, &map->room);
  if ((v = r.Member(j, "", "objects", true)) && r.Array(*v, "objects", kMaxMapObjects)) {
    map->objects.resize(v->size());
    std::set<int> object_ids;
    for (size_t i = 0; i < v->size() && r.ok(); ++i) {
      const std::string at = "objects[" + std::to_string(i) + "]";
      if (ReadObject(&r, (*v)[i], at, &map->objects[i]) && !object_ids.insert(map->objects[i].id).second)
        r.Fail(at + ".id", "object " + std::to_string(map->objects[i].id) + " is in the map twice");
    }
  }
  if ((v = r.Member(j, "", "trajectory", false)) && r.Array(*v, "trajectory", kMaxMapTrajectory)) {
    map->trajectory.resize(v->size());
    for (size_t i = 0; i < v->size() && r.ok(); ++i) {
      double p[4];
      if (r.Numbers((*v)[i], "trajectory[" + std::to_string(i) + "]", 4, p, 1e9))
        map->trajectory[i] = {p[0], {p[1], p[2], p[3]}};
    }
  }
  if ((v = r.Member(j, "", "cleaning", false))) {
    control::CleaningProgress c;
    if (ReadCleaning(&r, *v, &c)) map->cleaning = std::move(c);
  }
  if ((v = r.Member(j, "", "calibration", false))) {
    slam::CalibrationEstimate c;
    if (ReadCalibration(&r, *v, &c)) map->calibration = c;
  }
  if ((v = r.Member(j, "", "relocalized", false)) && r.Object(*v, "relocalized")) {
    robot::MapSnapshot::Relocalized rel;
    const json* f;
    if ((f = r.Member(*v, "relocalized", "t", true))) r.Number(*f, "relocalized.t", &rel.t, 1e9);
    if ((f = r.Member(*v, "relocalized", "hypotheses", true)))
      r.Int(*f, "relocalized.hypotheses", &rel.hypotheses, 0, INT32_MAX);
    if (r.ok()) map->relocalized = rel;
  }
  return r.ok();
}

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
  if (s.relocalize) j["relocalize"] = RelocalizeJson(*s.relocalize);
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
  if (m.relocalized) j["relocalized"] = {{"t", m.relocalized->t}, {"hypotheses", m.relocalized->hypotheses}};
  return j;
}

}  // namespace irslam
