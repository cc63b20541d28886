#include "daemon/config.h"

#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <vector>

#include "daemon/config_schema.h"
#include "io/file_io.h"
#include "io/json_text.h"

namespace irslam {
namespace {

using nlohmann::json;
using config::CustomKey;
using options::Entry;
using options::FormatNumber;

// A config file is a few kB; anything much larger is not one.
constexpr size_t kMaxConfigBytes = 1 << 20;

std::string Join(const std::vector<std::string>& path, std::string_view key) {
  std::string out;
  for (const auto& p : path) out += p + ".";
  return out + std::string(key);
}

// Parses: sets the options from the file's values, remembering which keys were
// used so unknown keys are reported by their full name. The first error wins.
class Reader : public config::Visitor {
 public:
  Reader(const json& top, std::string* error) : error_(error) { stack_.push_back({&top, {}}); }

  void Section(std::string_view name, std::string_view) override {
    const json* parent = stack_.back().j;
    stack_.back().used.insert(std::string(name));
    const json* sub = nullptr;
    if (parent != nullptr && parent->is_object() && parent->contains(name)) {
      sub = &parent->at(name);
      if (!sub->is_object()) {
        Fail(Join(path_, name) + " must be an object");
        sub = nullptr;
      }
    }
    path_.emplace_back(name);
    stack_.push_back({sub, {}});
  }

  void End() override {
    const Frame& f = stack_.back();
    if (f.j != nullptr) {
      for (const auto& [k, v] : f.j->items()) {
        if (!f.used.count(k)) Fail(Join(path_, OneLine(k)) + " is not a known key");
      }
    }
    stack_.pop_back();
    path_.pop_back();
  }

  void Custom(const CustomKey& key) override {
    const json* v = Use(key.name);
    if (v == nullptr) return;
    const std::string what = key.read(*v);
    if (!what.empty()) Fail(Join(path_, key.name) + what);
  }

  void Key(const Entry& e) override {
    const json* v = Use(e.name);
    if (v == nullptr) return;
    const std::string what = options::ReadEntry(*v, e);
    if (!what.empty()) Fail(Join(path_, e.name) + what);
  }

  // The top level's unknown keys.
  void Finish() {
    const Frame& f = stack_.front();
    for (const auto& [k, v] : f.j->items()) {
      if (!f.used.count(k)) Fail(OneLine(k) + " is not a known key");
    }
  }

 private:
  struct Frame {
    const json* j;  // nullptr: the section is absent (defaults)
    std::set<std::string, std::less<>> used;
  };
  const json* Use(std::string_view key) {
    Frame& f = stack_.back();
    f.used.insert(std::string(key));
    if (f.j == nullptr || !f.j->contains(key)) return nullptr;
    return &f.j->at(key);
  }
  void Fail(const std::string& what) {
    if (error_->empty()) *error_ = "config: " + what;
  }

  std::string* error_;
  std::vector<std::string> path_;
  std::vector<Frame> stack_;
};

// The effective configuration as a JSON value.
class Dumper : public config::Visitor {
 public:
  Dumper() { stack_.push_back(json::object()); }
  void Section(std::string_view name, std::string_view) override {
    names_.emplace_back(name);
    stack_.push_back(json::object());
  }
  void End() override {
    json done = std::move(stack_.back());
    stack_.pop_back();
    stack_.back()[names_.back()] = std::move(done);
    names_.pop_back();
  }
  void Custom(const CustomKey& key) override { stack_.back()[std::string(key.name)] = key.dump(); }
  void Key(const Entry& e) override { stack_.back()[std::string(e.name)] = options::EntryValue(e); }
  json Take() { return std::move(stack_.front()); }

 private:
  std::vector<json> stack_;
  std::vector<std::string> names_;
};

// The shipped config file: every key with its default, a comment above it with
// what it does, its unit and its bounds.
class Documenter : public config::Visitor {
 public:
  void Section(std::string_view name, std::string_view doc) override {
    Comment(doc);
    Item(Quote(name) + ": {");
    ++depth_;
    first_.push_back(true);
  }
  void End() override {
    --depth_;
    first_.pop_back();
    out_ += "\n" + Indent() + "}";
  }
  void Custom(const CustomKey& key) override {
    Comment(key.doc);
    Item(Quote(key.name) + ": " + DumpJson(key.dump()));
  }
  void Key(const Entry& e) override {
    std::string doc(e.doc);
    std::string range;
    if (e.kind == Entry::Kind::kNumber || e.kind == Entry::Kind::kInt) {
      range = FormatNumber(e.lo) + " .. " + FormatNumber(e.hi);
      if (!e.unit.empty()) range += " " + std::string(e.unit);
    }
    if (!range.empty()) doc += (doc.empty() ? "" : " ") + ("[" + range + "]");
    Comment(doc);
    Item(Quote(e.name) + ": " + DumpJson(options::EntryValue(e)));
  }
  std::string Take() { return out_ + "\n}\n"; }

 private:
  static std::string Quote(std::string_view s) { return "\"" + std::string(s) + "\""; }
  std::string Indent() const { return std::string(2 * static_cast<size_t>(depth_), ' '); }
  void Item(const std::string& text) {
    if (!first_.back()) out_ += ",";
    first_.back() = false;
    out_ += pending_comment_ + "\n" + Indent() + text;
    pending_comment_.clear();
  }
  void Comment(std::string_view doc) {
    if (doc.empty()) return;
    // Wrapped at ~90 columns.
    std::istringstream words{std::string(doc)};
    std::string word, line;
    while (words >> word) {
      if (!line.empty() && line.size() + word.size() + Indent().size() > 86) {
        pending_comment_ += "\n" + Indent() + "// " + line;
        line.clear();
      }
      line += (line.empty() ? "" : " ") + word;
    }
    if (!line.empty()) pending_comment_ += "\n" + Indent() + "// " + line;
  }

  std::string out_ =
      "// irslamd configuration: JSON with // comments. Every key is optional; the\n"
      "// values below are the built-in defaults. Unknown keys are rejected by name.\n"
      "// Units are SI: metres, seconds, radians, volts; [lo .. hi] are the bounds.\n"
      "// Generated from the option tables: `irslamd --print-default-config`.\n"
      "{";
  int depth_ = 1;
  std::vector<bool> first_{true};
  std::string pending_comment_;
};

}  // namespace

bool ParseConfig(std::string_view text, DaemonSettings* settings, std::string* error) {
  error->clear();
  const std::optional<json> parsed = ParseJsonText(text, error);
  if (!parsed) {
    *error = "config: " + *error;
    return false;
  }
  if (!parsed->is_object()) {
    *error = "config: the top level must be an object";
    return false;
  }
  DaemonSettings s = *settings;
  Reader reader(*parsed, error);
  config::WalkConfig(&s, &reader);
  reader.Finish();
  if (error->empty()) {
    const std::string check = config::CheckConfig(s);
    if (!check.empty()) *error = "config: " + check;
  }
  if (!error->empty()) return false;
  *settings = s;
  return true;
}

bool LoadConfigFile(const std::string& path, DaemonSettings* settings, std::string* error) {
  std::string text;
  if (!ReadRegularFile(path, kMaxConfigBytes, &text, error)) {
    *error = "config: " + *error;
    return false;
  }
  if (!ParseConfig(text, settings, error)) {
    *error = path + ": " + *error;
    return false;
  }
  return true;
}

bool LoadCoreConfigFile(const std::string& path, robot::CoreOptions* core, std::string* error) {
  DaemonSettings s;
  s.core = *core;
  if (!LoadConfigFile(path, &s, error)) return false;
  *core = s.core;
  return true;
}

std::string DumpConfig(const DaemonSettings& settings) {
  DaemonSettings s = settings;
  Dumper dumper;
  config::WalkConfig(&s, &dumper);
  return dumper.Take().dump(2);
}

std::string DocumentedConfig(const DaemonSettings& settings) {
  DaemonSettings s = settings;
  Documenter doc;
  config::WalkConfig(&s, &doc);
  return doc.Take();
}

}  // namespace irslam
