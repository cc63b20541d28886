// The Foxglove WebSocket protocol v1 (subprotocol foxglove.websocket.v1), the
// part irslam-foxglove speaks: serverInfo, advertise, status, the binary Message
// Data frame, and the client's subscribe/unsubscribe. Pure encoding and parsing:
// no socket here (the server is daemon/foxglove_server.h), so tests compare bytes.
#ifndef IRSLAM_DAEMON_FOXGLOVE_PROTOCOL_H_
#define IRSLAM_DAEMON_FOXGLOVE_PROTOCOL_H_

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace irslam::foxglove {

inline constexpr std::string_view kSubprotocol = "foxglove.websocket.v1";
inline constexpr uint8_t kOpMessageData = 0x01;
// Bytes before the payload of a Message Data frame: opcode, subscription id, time.
inline constexpr size_t kMessageDataHeaderBytes = 1 + 4 + 8;

// One channel the server advertises. Every irslam channel is JSON-encoded with a
// JSON Schema (schemaEncoding "jsonschema").
struct Channel {
  uint32_t id = 0;
  std::string topic;
  std::string schema_name;  // e.g. "foxglove.SceneUpdate"
  nlohmann::json schema;    // the JSON Schema (sent as its text)
};

// Status message levels.
enum class Level { kInfo = 0, kWarning = 1, kError = 2 };

nlohmann::json ServerInfoJson(const std::string& name, const std::string& session_id);
nlohmann::json AdvertiseJson(const std::vector<Channel>& channels);
nlohmann::json StatusJson(Level level, const std::string& message);

// Message Data (opcode 0x01): u8 opcode, u32 LE subscription id, u64 LE log time
// (ns), then the payload.
std::string MessageDataFrame(uint32_t subscription_id, uint64_t log_time_ns,
                             std::string_view payload);

// Whether a Sec-WebSocket-Protocol request header offers foxglove.websocket.v1
// (a comma-separated list).
bool OffersSubprotocol(std::string_view header);

// A client's text message, checked.
struct ClientOp {
  enum class Kind { kSubscribe, kUnsubscribe, kUnsupported };
  Kind kind = Kind::kUnsupported;
  std::string op;  // as sent (for kUnsupported: to name it in a status reply)
  std::vector<std::pair<uint32_t, uint32_t>> subscribe;  // (subscription id, channel id)
  std::vector<uint32_t> unsubscribe;                     // subscription ids
};

// Parses a text frame. Malformed input (not JSON, not an object, no string "op",
// subscribe/unsubscribe with missing or non-u32 ids) returns nullopt with *error
// set to one line; an op irslam-foxglove does not support is kUnsupported.
std::optional<ClientOp> ParseClientOp(std::string_view text, std::string* error);

// {"sec", "nsec"} of a time in ns (Foxglove's time and duration objects).
nlohmann::json TimeJson(uint64_t t_ns);

}  // namespace irslam::foxglove

#endif  // IRSLAM_DAEMON_FOXGLOVE_PROTOCOL_H_
