#include "io/option_json.h"

#include <cmath>
#include <cstdio>

#include "io/json_text.h"

namespace irslam::options {

std::string FormatNumber(double d) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.12g", d);
  return buf;
}

std::string ReadEntry(const nlohmann::json& v, const Entry& e) {
  switch (e.kind) {
    case Entry::Kind::kBool:
      if (!v.is_boolean()) return " must be true or false";
      *e.flag = v.get<bool>();
      return "";
    case Entry::Kind::kString:
      if (!v.is_string()) return " must be a string";
      *e.text = v.get<std::string>();
      return "";
    case Entry::Kind::kNumber:
    case Entry::Kind::kInt:
      break;
  }
  if (!v.is_number()) return " must be a number";
  const double d = v.get<double>();
  if (!(d >= e.lo && d <= e.hi)) {
    return " must be in [" + FormatNumber(e.lo) + ", " + FormatNumber(e.hi) + "] (got " + FormatNumber(d) + ")";
  }
  if (e.kind == Entry::Kind::kNumber) {
    *e.number = d;
  } else if (d != std::floor(d)) {
    return " must be an integer";
  } else {
    *e.integer = static_cast<int>(d);
  }
  return "";
}

nlohmann::json EntryValue(const Entry& e) {
  switch (e.kind) {
    case Entry::Kind::kBool: return *e.flag;
    case Entry::Kind::kString: return *e.text;
    case Entry::Kind::kInt: return *e.integer;
    case Entry::Kind::kNumber: break;
  }
  return *e.number;
}

bool ReadObject(const nlohmann::json& object, std::string_view path, const std::vector<Entry>& entries,
                std::string* error) {
  const std::string prefix = path.empty() ? "" : std::string(path) + ".";
  if (!object.is_object()) {
    *error = std::string(path) + " must be an object";
    return false;
  }
  for (const auto& [key, value] : object.items()) {
    const Entry* found = nullptr;
    for (const auto& e : entries) {
      if (e.name == key) found = &e;
    }
    if (found == nullptr) {
      *error = prefix + OneLine(key) + " is not a known key";
      return false;
    }
    const std::string what = ReadEntry(value, *found);
    if (!what.empty()) {
      *error = prefix + key + what;
      return false;
    }
  }
  return true;
}

}  // namespace irslam::options
