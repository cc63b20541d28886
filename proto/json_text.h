// Parses JSON text (comments allowed) into a value, or a one-line error with the
// position of the problem. One helper for config, world files and JSON-RPC.
#ifndef IRSLAM_PROTO_JSON_TEXT_H_
#define IRSLAM_PROTO_JSON_TEXT_H_

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

namespace irslam {

inline std::optional<nlohmann::json> ParseJsonText(std::string_view text, std::string* error) {
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

}  // namespace irslam

#endif  // IRSLAM_PROTO_JSON_TEXT_H_
