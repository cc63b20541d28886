// Parsing JSON text that comes from outside (config and world files, saved maps,
// API lines) with limits: nesting depth is checked on the raw text before the
// parser runs (a file nested 150,000 levels deep must not exhaust the stack), and
// every error is one line with the position of the problem. Comments are allowed.
#ifndef IRSLAM_IO_JSON_TEXT_H_
#define IRSLAM_IO_JSON_TEXT_H_

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

namespace irslam {

// Deeper than any file or request irslam reads legitimately (a map is 4 levels).
inline constexpr int kMaxJsonDepth = 64;

// Depth of [ and { nesting outside strings and comments; stops counting (and
// returns a value > max_depth) as soon as max_depth is exceeded.
int JsonNestingDepth(std::string_view text, int max_depth);

// The value, or nullopt and a one-line *error ("not valid JSON: ..." or "nested
// deeper than N levels").
std::optional<nlohmann::json> ParseJsonText(std::string_view text, std::string* error,
                                            int max_depth = kMaxJsonDepth);

// A key from a parsed file as it goes into a one-line message: control
// characters (a "\n" in a key) as JSON escapes (\n, \u0001), the rest as is.
std::string OneLine(std::string_view text);

// Serialises for output to a person or a socket: invalid UTF-8 in strings is
// replaced (U+FFFD), never thrown.
std::string DumpJson(const nlohmann::json& j, int indent = -1);

}  // namespace irslam

#endif  // IRSLAM_IO_JSON_TEXT_H_
