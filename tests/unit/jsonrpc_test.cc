#include <gtest/gtest.h>

#include "daemon/jsonrpc.h"

namespace irslam::rpc {
namespace {

int ErrorCode(const ParseResult& r) {
  const auto* e = std::get_if<nlohmann::json>(&r);
  return e ? (*e)["error"]["code"].get<int>() : 0;
}

TEST(JsonRpcTest, ParsesARequest) {
  auto r = ParseRequest(R"({"jsonrpc":"2.0","id":7,"method":"status","params":{"a":1}})");
  ASSERT_TRUE(std::holds_alternative<Request>(r));
  const auto& q = std::get<Request>(r);
  EXPECT_EQ(q.id, 7);
  EXPECT_EQ(q.method, "status");
  EXPECT_EQ(q.params["a"], 1);
  EXPECT_FALSE(q.notification);
}

TEST(JsonRpcTest, NotificationHasNoId) {
  auto r = ParseRequest(R"({"jsonrpc":"2.0","method":"stop"})");
  ASSERT_TRUE(std::holds_alternative<Request>(r));
  EXPECT_TRUE(std::get<Request>(r).notification);
}

TEST(JsonRpcTest, ErrorsUseTheStandardCodes) {
  EXPECT_EQ(ErrorCode(ParseRequest("{nope")), kParseError);
  EXPECT_EQ(ErrorCode(ParseRequest("\x01\x02\xff")), kParseError);
  EXPECT_EQ(ErrorCode(ParseRequest("[1,2]")), kInvalidRequest);
  EXPECT_EQ(ErrorCode(ParseRequest("42")), kInvalidRequest);
  EXPECT_EQ(ErrorCode(ParseRequest(R"({"id":1,"method":"status"})")), kInvalidRequest);
  EXPECT_EQ(ErrorCode(ParseRequest(R"({"jsonrpc":"1.0","id":1,"method":"status"})")), kInvalidRequest);
  EXPECT_EQ(ErrorCode(ParseRequest(R"({"jsonrpc":"2.0","id":1,"method":5})")), kInvalidRequest);
  EXPECT_EQ(ErrorCode(ParseRequest(R"({"jsonrpc":"2.0","id":{},"method":"x"})")), kInvalidRequest);
  EXPECT_EQ(ErrorCode(ParseRequest(R"({"jsonrpc":"2.0","id":1,"method":"x","params":3})")), kInvalidParams);
  // A number beyond a double (found by fuzzing: it used to end the daemon).
  EXPECT_EQ(ErrorCode(ParseRequest(R"({"jsonrpc":"2.0","id":1e999,"method":"status"})")), kParseError);
  EXPECT_EQ(ErrorCode(ParseRequest("88888888887e888887")), kParseError);
}

TEST(JsonRpcTest, ErrorKeepsTheIdWhenItIsKnown) {
  const auto r = ParseRequest(R"({"jsonrpc":"1.0","id":"abc","method":"x"})");
  EXPECT_EQ(std::get<nlohmann::json>(r)["id"], "abc");
  EXPECT_EQ(std::get<nlohmann::json>(ParseRequest("{"))["id"], nullptr);
}

}  // namespace
}  // namespace irslam::rpc
