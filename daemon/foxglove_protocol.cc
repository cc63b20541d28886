#include "daemon/foxglove_protocol.h"

#include <cmath>

namespace irslam::foxglove {

using nlohmann::json;

json ServerInfoJson(const std::string& name, const std::string& session_id) {
  // No optional capability: clients neither publish, call services nor set parameters.
  return {{"op", "serverInfo"},
          {"name", name},
          {"capabilities", json::array()},
          {"metadata", {{"frames", "map -> base_link"}}},
          {"sessionId", session_id}};
}

json AdvertiseJson(const std::vector<Channel>& channels) {
  json list = json::array();
  for (const auto& c : channels) {
    list.push_back({{"id", c.id},
                    {"topic", c.topic},
                    {"encoding", "json"},
                    {"schemaName", c.schema_name},
                    {"schema", c.schema.dump()},
                    {"schemaEncoding", "jsonschema"}});
  }
  return {{"op", "advertise"}, {"channels", list}};
}

json StatusJson(Level level, const std::string& message) {
  return {{"op", "status"}, {"level", static_cast<int>(level)}, {"message", message}};
}

std::string MessageDataFrame(uint32_t subscription_id, uint64_t log_time_ns,
                             std::string_view payload) {
  std::string f;
  f.reserve(kMessageDataHeaderBytes + payload.size());
  f.push_back(static_cast<char>(kOpMessageData));
  for (int i = 0; i < 4; ++i) f.push_back(static_cast<char>((subscription_id >> (8 * i)) & 0xff));
  for (int i = 0; i < 8; ++i) f.push_back(static_cast<char>((log_time_ns >> (8 * i)) & 0xff));
  f.append(payload);
  return f;
}

bool OffersSubprotocol(std::string_view header) {
  size_t pos = 0;
  while (pos <= header.size()) {
    size_t end = header.find(',', pos);
    if (end == std::string_view::npos) end = header.size();
    std::string_view item = header.substr(pos, end - pos);
    while (!item.empty() && (item.front() == ' ' || item.front() == '\t')) item.remove_prefix(1);
    while (!item.empty() && (item.back() == ' ' || item.back() == '\t')) item.remove_suffix(1);
    if (item == kSubprotocol) return true;
    pos = end + 1;
  }
  return false;
}

namespace {

// A JSON number that is a whole u32 (Foxglove ids are numbers).
std::optional<uint32_t> U32(const json& v) {
  if (v.is_number_unsigned()) {
    const auto u = v.get<uint64_t>();
    if (u <= 0xffffffffu) return static_cast<uint32_t>(u);
    return std::nullopt;
  }
  if (v.is_number_integer()) {
    const auto i = v.get<int64_t>();
    if (i >= 0 && i <= 0xffffffff) return static_cast<uint32_t>(i);
    return std::nullopt;
  }
  if (v.is_number_float()) {
    const double d = v.get<double>();
    if (d >= 0 && d <= 4294967295.0 && std::floor(d) == d) return static_cast<uint32_t>(d);
  }
  return std::nullopt;
}

// obj[key] as a u32, when obj is an object that has it (-1 otherwise: a plain
// integer, which GCC 12's flow analysis follows better than an optional here).
int64_t U32Field(const json& obj, const char* key) {
  if (!obj.is_object()) return -1;
  const auto it = obj.find(key);
  if (it == obj.end()) return -1;
  const auto v = U32(*it);
  return v ? static_cast<int64_t>(*v) : -1;
}

}  // namespace

std::optional<ClientOp> ParseClientOp(std::string_view text, std::string* error) {
  json j = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) {
    *error = "not JSON";
    return std::nullopt;
  }
  if (!j.is_object() || !j.contains("op") || !j["op"].is_string()) {
    *error = "not an object with a string \"op\"";
    return std::nullopt;
  }
  ClientOp op;
  op.op = j["op"].get<std::string>();
  if (op.op == "subscribe") {
    op.kind = ClientOp::Kind::kSubscribe;
    if (!j.contains("subscriptions") || !j["subscriptions"].is_array()) {
      *error = "subscribe without a \"subscriptions\" array";
      return std::nullopt;
    }
    for (const auto& s : j["subscriptions"]) {
      const int64_t id = U32Field(s, "id");
      const int64_t ch = U32Field(s, "channelId");
      if (id < 0 || ch < 0) {
        *error = "subscribe: each subscription needs a u32 \"id\" and \"channelId\"";
        return std::nullopt;
      }
      op.subscribe.emplace_back(static_cast<uint32_t>(id), static_cast<uint32_t>(ch));
    }
  } else if (op.op == "unsubscribe") {
    op.kind = ClientOp::Kind::kUnsubscribe;
    if (!j.contains("subscriptionIds") || !j["subscriptionIds"].is_array()) {
      *error = "unsubscribe without a \"subscriptionIds\" array";
      return std::nullopt;
    }
    for (const auto& s : j["subscriptionIds"]) {
      const auto id = U32(s);
      if (!id) {
        *error = "unsubscribe: subscription ids must be u32 numbers";
        return std::nullopt;
      }
      op.unsubscribe.push_back(*id);
    }
  }
  return op;
}

json TimeJson(uint64_t t_ns) {
  return {{"sec", static_cast<uint32_t>(t_ns / 1000000000u)},
          {"nsec", static_cast<uint32_t>(t_ns % 1000000000u)}};
}

}  // namespace irslam::foxglove
