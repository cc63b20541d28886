#include "io/json_text.h"

#include <cstdio>

namespace irslam {

int JsonNestingDepth(std::string_view text, int max_depth) {
  int depth = 0, deepest = 0;
  bool in_string = false, escaped = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (escaped) {
        escaped = false;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
      }
      continue;
    }
    if (c == '"') {
      in_string = true;
    } else if (c == '/' && i + 1 < text.size() && text[i + 1] == '/') {
      const size_t end = text.find('\n', i);
      if (end == std::string_view::npos) break;
      i = end;
    } else if (c == '/' && i + 1 < text.size() && text[i + 1] == '*') {
      const size_t end = text.find("*/", i + 2);
      if (end == std::string_view::npos) break;
      i = end + 1;
    } else if (c == '[' || c == '{') {
      if (++depth > deepest) deepest = depth;
      if (deepest > max_depth) return deepest;
    } else if (c == ']' || c == '}') {
      if (depth > 0) --depth;
    }
  }
  return deepest;
}

std::optional<nlohmann::json> ParseJsonText(std::string_view text, std::string* error,
                                            int max_depth) {
  if (JsonNestingDepth(text, max_depth) > max_depth) {
    *error = "nested deeper than " + std::to_string(max_depth) + " levels";
    return std::nullopt;
  }
  nlohmann::json j = nlohmann::json::parse(text.begin(), text.end(), nullptr,
                                           /*allow_exceptions=*/false, /*ignore_comments=*/true);
  if (!j.is_discarded()) return j;
  // Only on failure: parse again with exceptions to learn where it broke.
  try {
    j = nlohmann::json::parse(text.begin(), text.end(), nullptr, true, true);
  } catch (const nlohmann::json::exception& ex) {
    // parse_error, but also out_of_range (a number too large for a double, e.g.
    // 1e999: found by fuzzing; before, it escaped and ended the process).
    std::string what = ex.what();
    const auto pos = what.find("] ");
    *error = "not valid JSON: " + (pos == std::string::npos ? what : what.substr(pos + 2));
    return std::nullopt;
  }
  *error = "not valid JSON";
  return std::nullopt;
}

std::string OneLine(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u != 0x7f) {
      out += c;
    } else if (c == '\n') {
      out += "\\n";
    } else if (c == '\r') {
      out += "\\r";
    } else if (c == '\t') {
      out += "\\t";
    } else {
      char esc[16];
      std::snprintf(esc, sizeof esc, "\\u%04x", u);
      out += esc;
    }
  }
  return out;
}

std::string DumpJson(const nlohmann::json& j, int indent) {
  return j.dump(indent, ' ', /*ensure_ascii=*/false, nlohmann::json::error_handler_t::replace);
}

}  // namespace irslam
