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

TEST(JsonRpcTest, MessageTextNeverThrowsOnInvalidUtf8) {
  // Strict dump() threw type_error 316 here (SIGABRT in the daemon).
  const auto parsed = ParseRequest("{\"jsonrpc\":\"2.0\",\"id\":1,\"method\":\"\xff\"}");
  const std::string text = MessageText(std::get<nlohmann::json>(parsed));
  EXPECT_EQ(text.find('\xff'), std::string::npos);
  EXPECT_NE(text.find("\xef\xbf\xbd"), std::string::npos) << text;
  EXPECT_EQ(MessageText(MakeError(nullptr, kMethodNotFound, "method not found: \xc3")),
            "{\"error\":{\"code\":-32601,\"message\":\"method not found: \xef\xbf\xbd\"},\"id\":null,"
            "\"jsonrpc\":\"2.0\"}");
}

TEST(JsonRpcTest, ResultTextIsWhatMessageTextMakesOfTheResult) {
  const nlohmann::json result = {{"state", "idle"}, {"pose", {1.5, -2, 0.25}}, {"s", "\xff"}};
  for (const nlohmann::json& id : {nlohmann::json(7), nlohmann::json("abc"), nlohmann::json(nullptr)}) {
    EXPECT_EQ(ResultText(id, MessageText(result)), MessageText(MakeResult(id, result)));
  }
}

TEST(JsonRpcTest, EscapeForLogKeepsOneLineAndCapsTheLength) {
  // A method name with a newline and a priority prefix forged log lines.
  EXPECT_EQ(EscapeForLog("stop\n<0>irslamd: fake"), "stop\\x0a<0>irslamd: fake");
  EXPECT_EQ(EscapeForLog("a\\b\x7f\xff\r"), "a\\x5cb\\x7f\\xff\\x0d");
  EXPECT_EQ(EscapeForLog(std::string(100, 'x'), 8), "xxxxxxxx...");
  EXPECT_EQ(EscapeForLog("status"), "status");
}

}  // namespace
}  // namespace irslam::rpc
