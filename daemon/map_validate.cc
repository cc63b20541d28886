#include "daemon/map_validate.h"

#include <initializer_list>

namespace irslam {
namespace {

using nlohmann::json;

bool Numbers(const json& j, size_t n) {
  if (!j.is_array() || j.size() != n) return false;
  for (const auto& x : j) {
    if (!x.is_number()) return false;
  }
  return true;
}

bool Matrix(const json& j, size_t n) {
  if (!j.is_array() || j.size() != n) return false;
  for (const auto& row : j) {
    if (!Numbers(row, n)) return false;
  }
  return true;
}

bool Integers(const json& j) {
  if (!j.is_array()) return false;
  for (const auto& x : j) {
    if (!x.is_number_integer()) return false;
  }
  return true;
}

// Records the first failure: *error = where + ": " + what.
class Checker {
 public:
  explicit Checker(std::string* error) : error_(error) {}
  bool ok() const { return ok_; }
  void Require(bool good, const std::string& where, const char* what) {
    if (ok_ && !good) {
      ok_ = false;
      *error_ = "map." + where + ": " + what;
    }
  }

 private:
  std::string* error_;
  bool ok_ = true;
};

void CheckLine(const json& l, const std::string& at, Checker* c) {
  c->Require(l.is_object(), at, "not an object");
  if (!c->ok()) return;
  c->Require(l.contains("id") && l["id"].is_number_integer(), at + ".id", "not an integer");
  for (const char* k : {"rho", "theta"}) {
    c->Require(l.contains(k) && l[k].is_number(), at + "." + k, "not a number");
  }
  c->Require(l.contains("cov") && Matrix(l["cov"], 2), at + ".cov", "not a 2x2 matrix of numbers");
  for (const char* k : {"p0", "p1"}) {
    c->Require(l.contains(k) && Numbers(l[k], 2), at + "." + k, "not an array of 2 numbers");
  }
  c->Require(!l.contains("length") || l["length"].is_number(), at + ".length", "not a number");
  c->Require(!l.contains("merged") || Integers(l["merged"]), at + ".merged", "not an array of integers");
}

void CheckObject(const json& o, const std::string& at, Checker* c) {
  c->Require(o.is_object(), at, "not an object");
  if (!c->ok()) return;
  c->Require(o.contains("id") && o["id"].is_number_integer(), at + ".id", "not an integer");
  c->Require(o.contains("kind") && o["kind"].is_string(), at + ".kind", "not a string");
  c->Require(o.contains("lines") && Integers(o["lines"]), at + ".lines", "not an array of integers");
  c->Require(!o.contains("complete") || o["complete"].is_boolean(), at + ".complete", "not a boolean");
  c->Require(!o.contains("box") || Numbers(o["box"], 4), at + ".box", "not an array of 4 numbers");
}

void CheckRoom(const json& r, Checker* c) {
  c->Require(r.is_object(), "room", "not an object");
  if (!c->ok()) return;
  if (r.contains("walls")) {
    const json& w = r["walls"];
    c->Require(w.is_object(), "room.walls", "not an object");
    if (!c->ok()) return;
    for (const auto& item : w.items()) {
      c->Require(Integers(item.value()), "room.walls." + item.key(), "not an array of integers");
    }
  }
  c->Require(!r.contains("box") || r["box"].is_null() || Numbers(r["box"], 4), "room.box",
             "not null or an array of 4 numbers");
}

}  // namespace

bool ValidateMapBody(const json& map, std::string* error) {
  Checker c(error);
  c.Require(map.is_object(), "", "not an object");
  if (!c.ok()) return false;
  for (const char* k : {"frame", "state"}) {
    c.Require(map.contains(k) && map[k].is_string(), k, "missing or not a string");
  }
  for (const char* k : {"lines", "objects"}) {
    c.Require(map.contains(k) && map[k].is_array(), k, "missing or not an array");
  }
  if (!c.ok()) return false;
  c.Require(!map.contains("pose") || Numbers(map["pose"], 3), "pose", "not an array of 3 numbers");
  c.Require(!map.contains("pose_cov") || Matrix(map["pose_cov"], 3), "pose_cov", "not a 3x3 matrix of numbers");
  for (size_t i = 0; i < map["lines"].size() && c.ok(); ++i) {
    CheckLine(map["lines"][i], "lines[" + std::to_string(i) + "]", &c);
  }
  for (size_t i = 0; i < map["objects"].size() && c.ok(); ++i) {
    CheckObject(map["objects"][i], "objects[" + std::to_string(i) + "]", &c);
  }
  if (c.ok() && map.contains("calibration")) {
    const json& k = map["calibration"];
    c.Require(k.is_object(), "calibration", "not an object");
    if (c.ok()) {
      c.Require(k.contains("scale") && Numbers(k["scale"], 3), "calibration.scale", "not an array of 3 numbers");
      c.Require(k.contains("std") && Numbers(k["std"], 3), "calibration.std", "not an array of 3 numbers");
      for (const char* key : {"ratio", "ratio_std"}) {
        c.Require(!k.contains(key) || k[key].is_number(), std::string("calibration.") + key, "not a number");
      }
    }
  }
  if (c.ok() && map.contains("room")) CheckRoom(map["room"], &c);
  if (c.ok() && map.contains("trajectory")) {
    const json& t = map["trajectory"];
    c.Require(t.is_array(), "trajectory", "not an array");
    for (size_t i = 0; c.ok() && i < t.size(); ++i) {
      c.Require(Numbers(t[i], 4), "trajectory[" + std::to_string(i) + "]", "not an array of 4 numbers");
    }
  }
  return c.ok();
}

}  // namespace irslam
