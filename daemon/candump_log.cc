#include "daemon/candump_log.h"

#include <charconv>
#include <cinttypes>
#include <cmath>
#include <cstdio>

#include "proto/codec.h"

namespace irslam {
namespace {

bool IsHex(char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F'); }

bool AllHex(std::string_view s) {
  for (char c : s) {
    if (!IsHex(c)) return false;
  }
  return true;
}

// "(SEC.FRAC)" -> nanoseconds; FRAC has 1 to 9 digits.
bool ParseStamp(std::string_view s, int64_t* ns) {
  if (s.size() < 4 || s.front() != '(' || s.back() != ')') return false;
  s = s.substr(1, s.size() - 2);
  const auto dot = s.find('.');
  if (dot == std::string_view::npos || dot == 0 || dot > 10) return false;
  const std::string_view sec = s.substr(0, dot), frac = s.substr(dot + 1);
  if (frac.empty() || frac.size() > 9) return false;
  int64_t whole = 0, part = 0;
  for (char c : sec) {
    if (c < '0' || c > '9') return false;
    whole = whole * 10 + (c - '0');
  }
  for (char c : frac) {
    if (c < '0' || c > '9') return false;
    part = part * 10 + (c - '0');
  }
  if (whole >= 9000000000) return false;  // nanoseconds in int64_t (until 2255)
  for (size_t i = frac.size(); i < 9; ++i) part *= 10;
  *ns = whole * 1000000000 + part;
  return true;
}

// Splits off the next space-separated token.
std::string_view NextToken(std::string_view* rest) {
  size_t b = 0;
  while (b < rest->size() && ((*rest)[b] == ' ' || (*rest)[b] == '\t')) ++b;
  size_t e = b;
  while (e < rest->size() && (*rest)[e] != ' ' && (*rest)[e] != '\t') ++e;
  const std::string_view tok = rest->substr(b, e - b);
  *rest = rest->substr(e);
  return tok;
}

}  // namespace

bool ParseLogLine(std::string_view line, LogLine* out, std::string* error) {
  *out = LogLine{};
  if (line.size() > kMaxLogLineBytes) {
    *error = "line longer than " + std::to_string(kMaxLogLineBytes) + " bytes";
    return false;
  }
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  std::string_view rest = line;
  const std::string_view stamp = NextToken(&rest);
  if (stamp.empty()) return true;  // blank
  if (stamp.front() == '#') {
    out->kind = LogLine::Kind::kComment;
    return true;
  }
  if (!ParseStamp(stamp, &out->stamp_ns)) {
    *error = "bad time stamp (want \"(SECONDS.MICROS)\")";
    return false;
  }
  const std::string_view iface = NextToken(&rest);
  const std::string_view text = NextToken(&rest);
  const std::string_view flag = NextToken(&rest);  // candump -x adds R/T (rx/tx) here
  if (iface.empty() || text.empty()) {
    *error = "truncated line (want \"(STAMP) IFACE ID#DATA\")";
    return false;
  }
  if (iface.size() >= 64) {
    *error = "interface name too long";
    return false;
  }
  if (!(flag.empty() || flag == "R" || flag == "T") || !NextToken(&rest).empty()) {
    *error = "unexpected text after the frame";
    return false;
  }
  out->iface = std::string(iface);
  const auto hash = text.find('#');
  if (hash == std::string_view::npos || hash == 0 || !AllHex(text.substr(0, hash))) {
    *error = "bad frame (want ID#DATA in hex)";
    return false;
  }
  const std::string_view id = text.substr(0, hash), data = text.substr(hash + 1);
  if (id.size() == 8 || (!data.empty() && (data.front() == '#' || data.front() == 'R' || data.front() == 'r'))) {
    // Extended id, CAN FD (ID##FLAGS DATA) or remote request: checked loosely, never ours.
    if (id.size() != 3 && id.size() != 8) {
      *error = "bad frame id (want 3 or 8 hex digits)";
      return false;
    }
    out->kind = LogLine::Kind::kForeign;
    return true;
  }
  if (id.size() != 3) {
    *error = "bad frame id (want 3 or 8 hex digits)";
    return false;
  }
  if (!proto::ParseCandumpString(text, &out->frame)) {
    *error = "bad frame data (want up to 8 bytes in hex)";
    return false;
  }
  out->kind = LogLine::Kind::kFrame;
  return true;
}

std::string FormatLogLine(int64_t stamp_ns, std::string_view iface, const can_frame& frame) {
  char stamp[48];
  const int64_t us = stamp_ns / 1000;
  std::snprintf(stamp, sizeof stamp, "(%010" PRId64 ".%06" PRId64 ") ", us / 1000000, us % 1000000);
  std::string line = stamp;
  line += iface;
  line += ' ';
  line += proto::ToCandumpString(frame);
  return line;
}

std::string FormatEventComment(int64_t stamp_ns, std::string_view name) {
  can_frame none{};
  std::string line = FormatLogLine(stamp_ns, "", none);  // "(STAMP)  000#"
  line.resize(line.find(')') + 1);
  return "# irslamd-event " + line + " " + std::string(name);
}

std::optional<LogEvent> ParseEventComment(std::string_view comment) {
  constexpr std::string_view kTag = "# irslamd-event ";
  if (comment.substr(0, kTag.size()) != kTag) return std::nullopt;
  std::string_view rest = comment.substr(kTag.size());
  LogEvent e;
  if (!ParseStamp(NextToken(&rest), &e.stamp_ns)) return std::nullopt;
  e.name = std::string(NextToken(&rest));
  if (e.name.empty() || !NextToken(&rest).empty()) return std::nullopt;
  return e;
}

std::string FormatRecordHeader(const RecordHeader& h) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "# irslamd-record v1 origin=%" PRId64 ".%09" PRId64 " time_scale=%.17g period_s=%.17g",
                h.origin_ns / 1000000000, h.origin_ns % 1000000000, h.time_scale, h.period_s);
  return buf;
}

std::optional<RecordHeader> ParseRecordHeader(std::string_view comment) {
  constexpr std::string_view kTag = "# irslamd-record v1 ";
  if (comment.substr(0, kTag.size()) != kTag) return std::nullopt;
  std::string_view rest = comment.substr(kTag.size());
  RecordHeader h;
  bool origin = false, scale = false, period = false;
  for (std::string_view tok = NextToken(&rest); !tok.empty(); tok = NextToken(&rest)) {
    const auto eq = tok.find('=');
    if (eq == std::string_view::npos) return std::nullopt;
    const std::string_view key = tok.substr(0, eq), value = tok.substr(eq + 1);
    if (key == "origin") {
      // (Appended, not "(" + std::string: GCC PR 105329, see CMakeLists.txt.)
      std::string stamp = "(";
      stamp.append(value).append(")");
      origin = ParseStamp(stamp, &h.origin_ns);
    } else if (key == "time_scale" || key == "period_s") {
      double v = 0;
      const auto r = std::from_chars(value.data(), value.data() + value.size(), v);
      if (r.ec != std::errc() || r.ptr != value.data() + value.size() || !std::isfinite(v) || v <= 0) {
        return std::nullopt;
      }
      (key == "time_scale" ? h.time_scale : h.period_s) = v;
      (key == "time_scale" ? scale : period) = true;
    }  // other keys: from a later version, ignored
  }
  if (!origin || !scale || !period) return std::nullopt;
  return h;
}

}  // namespace irslam
