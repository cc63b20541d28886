// irslam-foxglove's encoding: the Foxglove WebSocket protocol frames and ops, and
// each channel's message built from real status/map values; and the server with a
// Beast client on loopback (subscribe, latest message at once, bad input, slow client).
#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <cmath>
#include <cstring>

#include "daemon/foxglove_bridge.h"
#include "daemon/foxglove_messages.h"
#include "daemon/foxglove_protocol.h"
#include "daemon/foxglove_server.h"

namespace irslam::foxglove {
namespace {

using nlohmann::json;

constexpr uint64_t kT = 1700000000123456789ull;

TEST(FoxgloveProtocolTest, MessageDataFrameIsOpcodeSubscriptionTimeLittleEndianThenPayload) {
  const std::string f = MessageDataFrame(0x04030201u, 0x0c0b0a0908070605ull, "{\"a\":1}");
  ASSERT_EQ(f.size(), 13u + 7u);
  const unsigned char expected[13] = {0x01, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06,
                                      0x07, 0x08, 0x09, 0x0a, 0x0b, 0x0c};
  EXPECT_EQ(std::memcmp(f.data(), expected, 13), 0);
  EXPECT_EQ(f.substr(13), "{\"a\":1}");
  EXPECT_EQ(kMessageDataHeaderBytes, 13u);
}

TEST(FoxgloveProtocolTest, ServerInfoAndAdvertiseCarryWhatTheSpecAsks) {
  const json info = ServerInfoJson("irslam-foxglove", "s1");
  EXPECT_EQ(info["op"], "serverInfo");
  EXPECT_EQ(info["name"], "irslam-foxglove");
  EXPECT_TRUE(info["capabilities"].is_array());
  EXPECT_EQ(info["sessionId"], "s1");
  const json adv = AdvertiseJson(IrslamChannels());
  EXPECT_EQ(adv["op"], "advertise");
  ASSERT_EQ(adv["channels"].size(), 8u);
  std::map<std::string, std::string> topics;
  for (const auto& c : adv["channels"]) {
    EXPECT_EQ(c["encoding"], "json");
    EXPECT_EQ(c["schemaEncoding"], "jsonschema");
    EXPECT_TRUE(c["id"].is_number_unsigned());
    // The schema is JSON Schema text whose title is the schema name.
    const json schema = json::parse(c["schema"].get<std::string>());
    EXPECT_EQ(schema["title"], c["schemaName"]);
    topics[c["topic"]] = c["schemaName"];
  }
  EXPECT_EQ(topics["/tf"], "foxglove.FrameTransform");
  EXPECT_EQ(topics["/pose"], "foxglove.PoseInFrame");
  EXPECT_EQ(topics["/trajectory"], "foxglove.PosesInFrame");
  EXPECT_EQ(topics["/map/lines"], "foxglove.SceneUpdate");
  EXPECT_EQ(topics["/map/objects"], "foxglove.SceneUpdate");
  EXPECT_EQ(topics["/map/room"], "foxglove.SceneUpdate");
  EXPECT_EQ(topics["/ir"], "foxglove.SceneUpdate");
  EXPECT_EQ(topics["/state"], "irslam.State");
}

TEST(FoxgloveProtocolTest, SchemasHaveFoxglovesFieldsAndEnums) {
  const json su = SchemaFor("foxglove.SceneUpdate");
  const json& entity = su["properties"]["entities"]["items"];
  EXPECT_EQ(entity["title"], "foxglove.SceneEntity");
  for (const char* k :
       {"timestamp", "frame_id", "id", "lifetime", "frame_locked", "metadata", "arrows", "cubes",
        "spheres", "cylinders", "lines", "triangles", "texts", "models"}) {
    EXPECT_TRUE(entity["properties"].contains(k)) << k;
  }
  const json& line = entity["properties"]["lines"]["items"];
  EXPECT_EQ(line["title"], "foxglove.LinePrimitive");
  const json& type = line["properties"]["type"];
  ASSERT_EQ(type["oneOf"].size(), 3u);
  EXPECT_EQ(type["oneOf"][1]["title"], "LINE_LOOP");
  EXPECT_EQ(type["oneOf"][1]["const"], 1);
  EXPECT_EQ(type["oneOf"][2]["title"], "LINE_LIST");
  EXPECT_EQ(type["oneOf"][2]["const"], 2);
  EXPECT_EQ(su["properties"]["deletions"]["items"]["properties"]["type"]["oneOf"][1]["title"],
            "ALL");
  const json ft = SchemaFor("foxglove.FrameTransform");
  for (const char* k :
       {"timestamp", "parent_frame_id", "child_frame_id", "translation", "rotation"}) {
    EXPECT_TRUE(ft["properties"].contains(k)) << k;
  }
  EXPECT_EQ(ft["properties"]["rotation"]["title"], "foxglove.Quaternion");
  EXPECT_EQ(ft["properties"]["timestamp"]["properties"]["nsec"]["maximum"], 999999999);
  EXPECT_EQ(SchemaFor("foxglove.PosesInFrame")["properties"]["poses"]["items"]["title"],
            "foxglove.Pose");
}

TEST(FoxgloveProtocolTest, ParsesSubscribeAndUnsubscribe) {
  std::string error;
  auto op = ParseClientOp(
      R"({"op":"subscribe","subscriptions":[{"id":0,"channelId":3},{"id":7,"channelId":5}]})",
      &error);
  ASSERT_TRUE(op) << error;
  EXPECT_EQ(op->kind, ClientOp::Kind::kSubscribe);
  ASSERT_EQ(op->subscribe.size(), 2u);
  EXPECT_EQ(op->subscribe[0], std::make_pair(0u, 3u));
  EXPECT_EQ(op->subscribe[1], std::make_pair(7u, 5u));
  op = ParseClientOp(R"({"op":"unsubscribe","subscriptionIds":[0,7]})", &error);
  ASSERT_TRUE(op) << error;
  EXPECT_EQ(op->kind, ClientOp::Kind::kUnsubscribe);
  EXPECT_EQ(op->unsubscribe, (std::vector<uint32_t>{0, 7}));
  op = ParseClientOp(R"({"op":"getParameters","parameterNames":[]})", &error);
  ASSERT_TRUE(op);
  EXPECT_EQ(op->kind, ClientOp::Kind::kUnsupported);
  EXPECT_EQ(op->op, "getParameters");
}

TEST(FoxgloveProtocolTest, RejectsMalformedClientOps) {
  std::string error;
  for (const char* bad :
       {"not json", "[1,2]", R"({"subscriptions":[]})", R"({"op":3})", R"({"op":"subscribe"})",
        R"({"op":"subscribe","subscriptions":[{"id":-1,"channelId":1}]})",
        R"({"op":"subscribe","subscriptions":[{"id":1.5,"channelId":1}]})",
        R"({"op":"subscribe","subscriptions":[{"id":1}]})",
        R"({"op":"subscribe","subscriptions":[{"id":4294967296,"channelId":1}]})",
        R"({"op":"unsubscribe","subscriptionIds":["a"]})"}) {
    error.clear();
    EXPECT_FALSE(ParseClientOp(bad, &error)) << bad;
    EXPECT_FALSE(error.empty()) << bad;
  }
}

TEST(FoxgloveProtocolTest, FindsTheSubprotocolInTheOfferedList) {
  EXPECT_TRUE(OffersSubprotocol("foxglove.websocket.v1"));
  EXPECT_TRUE(OffersSubprotocol("x, foxglove.websocket.v1 ,y"));
  EXPECT_FALSE(OffersSubprotocol("foxglove.websocket.v2"));
  EXPECT_FALSE(OffersSubprotocol(""));
}

// A status as irslamd sends it (contracts §6; the keys irslam-foxglove reads).
json Status() {
  return json::parse(R"({
    "state": "clean", "reason": "", "behaviour": "follow_path", "robot_time": 123.5,
    "pose": [1.25, -0.5, 1.5707963267948966], "pose_std": [0.01, 0.01, 0.002],
    "lines": 9, "objects": 2,
    "ir_ranges": [0.5, null, 0.3, null, null, null, 1.0],
    "controller": {"alive": true, "battery": 14.4},
    "safety": {"estop": false},
    "cleaning": {"state": "running", "fraction": 0.375, "covered_m2": 3.0, "total_m2": 8.0, "eta_s": 420.0}
  })");
}

json Map() {
  return json::parse(R"({
    "frame": "map", "state": "done", "pose": [0.1, 0.2, 0.0],
    "lines": [
      {"id": 1, "rho": 0.0, "theta": 1.5707963267948966, "cov": [[0.0004, 0.0], [0.0, 0.0001]],
       "p0": [0.0, 0.0], "p1": [4.0, 0.0], "length": 4.0, "observations": 12},
      {"id": 3, "rho": 4.0, "theta": 0.0, "cov": [[0.0009, 0.0], [0.0, 0.0004]],
       "p0": [4.0, 0.0], "p1": [4.0, 3.0], "length": 3.0, "observations": 5}
    ],
    "room": {"walls": {"bottom": [1], "right": [3], "top": [], "left": []}, "box": [0.0, 0.0, 4.0, 3.0]},
    "objects": [{"id": 1, "kind": "free", "lines": [8, 9], "complete": true, "box": [1.0, 1.0, 1.5, 2.0]},
                {"id": 2, "kind": "wall_contact", "lines": [10], "complete": false, "box": [3.0, 2.0, 4.0, 3.0]}],
    "trajectory": [[0.0, 0.0, 0.0, 0.0], [0.25, 0.05, 0.0, 0.0], [0.5, 0.1, 0.0, 0.1], [0.75, 0.15, 0.01, 0.2],
                   [1.0, 0.2, 0.02, 0.3]]
  })");
}

TEST(FoxgloveMessagesTest, FrameTransformIsMapToBaseLinkFromTheStatusPose) {
  const auto m = FrameTransformMessage(Status(), kT);
  ASSERT_TRUE(m);
  EXPECT_EQ((*m)["timestamp"]["sec"], 1700000000u);
  EXPECT_EQ((*m)["timestamp"]["nsec"], 123456789u);
  EXPECT_EQ((*m)["parent_frame_id"], "map");
  EXPECT_EQ((*m)["child_frame_id"], "base_link");
  EXPECT_DOUBLE_EQ((*m)["translation"]["x"].get<double>(), 1.25);
  EXPECT_DOUBLE_EQ((*m)["translation"]["y"].get<double>(), -0.5);
  EXPECT_DOUBLE_EQ((*m)["translation"]["z"].get<double>(), 0.0);
  // Yaw 90 degrees about z.
  EXPECT_NEAR((*m)["rotation"]["z"].get<double>(), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR((*m)["rotation"]["w"].get<double>(), std::sqrt(0.5), 1e-12);
  EXPECT_DOUBLE_EQ((*m)["rotation"]["x"].get<double>(), 0.0);
  EXPECT_FALSE(FrameTransformMessage(json::object(), kT));
  EXPECT_FALSE(FrameTransformMessage(json{{"pose", {1, "x", 2}}}, kT));
}

TEST(FoxgloveMessagesTest, PoseInFrameIsTheStatusPoseInTheMapFrame) {
  const auto m = PoseMessage(Status(), kT);
  ASSERT_TRUE(m);
  EXPECT_EQ((*m)["frame_id"], "map");
  EXPECT_DOUBLE_EQ((*m)["pose"]["position"]["x"].get<double>(), 1.25);
  EXPECT_DOUBLE_EQ((*m)["pose"]["position"]["y"].get<double>(), -0.5);
  const double yaw = 2 * std::atan2((*m)["pose"]["orientation"]["z"].get<double>(),
                                    (*m)["pose"]["orientation"]["w"].get<double>());
  EXPECT_NEAR(yaw, M_PI / 2, 1e-12);
}

TEST(FoxgloveMessagesTest, StateCarriesStateReasonAndCleaningProgress) {
  const json m = StateMessage(Status(), true, "", kT);
  EXPECT_EQ(m["connected"], true);
  EXPECT_EQ(m["state"], "clean");
  EXPECT_EQ(m["behaviour"], "follow_path");
  EXPECT_DOUBLE_EQ(m["robot_time"].get<double>(), 123.5);
  EXPECT_DOUBLE_EQ(m["pose"]["theta"].get<double>(), 1.5707963267948966);
  EXPECT_EQ(m["lines"], 9);
  EXPECT_EQ(m["objects"], 2);
  EXPECT_EQ(m["cleaning_state"], "running");
  EXPECT_DOUBLE_EQ(m["cleaning_fraction"].get<double>(), 0.375);
  EXPECT_DOUBLE_EQ(m["cleaning_total_m2"].get<double>(), 8.0);
  EXPECT_DOUBLE_EQ(m["cleaning_eta_s"].get<double>(), 420.0);
  EXPECT_EQ(m["controller_alive"], true);
  EXPECT_DOUBLE_EQ(m["battery_v"].get<double>(), 14.4);
  // Every key the message has is in its schema.
  const json schema = SchemaFor("irslam.State");
  for (const auto& [k, v] : m.items()) EXPECT_TRUE(schema["properties"].contains(k)) << k;
  const json down = StateMessage(json(), false, "cannot reach irslamd", kT);
  EXPECT_EQ(down["connected"], false);
  EXPECT_EQ(down["state"], "disconnected");
  EXPECT_EQ(down["error"], "cannot reach irslamd");
  EXPECT_TRUE(down["cleaning_eta_s"].is_null());
}

TEST(FoxgloveMessagesTest, IrRaysGoFromEachMountToItsReading) {
  RobotShape robot;
  for (int i = 0; i < kNumIrSensors; ++i) {
    const double a = -M_PI / 2 + M_PI * i / (kNumIrSensors - 1);
    robot.mounts[i] = {0.05 * std::cos(a), 0.05 * std::sin(a), a};
  }
  robot.max_range_m = 1.2;
  const auto m = IrMessage(Status(), robot, kT);
  ASSERT_TRUE(m);
  EXPECT_EQ((*m)["deletions"][0]["type"], 1);
  const json& rays = (*m)["entities"][0];
  EXPECT_EQ(rays["frame_id"], "base_link");
  EXPECT_EQ(rays["frame_locked"], true);
  const json& hits = rays["lines"][0];
  EXPECT_EQ(hits["type"], 2);            // LINE_LIST
  ASSERT_EQ(hits["points"].size(), 6u);  // three readings
  // Sensor 0 looks right (-90 deg): its reading 0.5 m ends at y = -0.55.
  EXPECT_NEAR(hits["points"][1]["x"].get<double>(), 0.0, 1e-12);
  EXPECT_NEAR(hits["points"][1]["y"].get<double>(), -0.55, 1e-12);
  // Sensor 6 looks left with 1.0 m.
  EXPECT_NEAR(hits["points"][5]["y"].get<double>(), 1.05, 1e-12);
  const json& misses = rays["lines"][1];
  ASSERT_EQ(misses["points"].size(), 8u);  // four without a reading, grey, max range
  // Sensor 3 looks ahead: no reading, drawn to 1.2 m.
  EXPECT_NEAR(misses["points"][3]["x"].get<double>(), 1.25, 1e-12);
  EXPECT_EQ(rays["spheres"].size(), 3u);
  EXPECT_EQ(rays["metadata"][1]["value"], "none");
  EXPECT_EQ(rays["metadata"][0]["value"], "0.500");
}

TEST(FoxgloveMessagesTest, TrajectoryKeepsFirstAndLastWhenThinned) {
  json m = TrajectoryMessage(Map(), kT);
  EXPECT_EQ(m["frame_id"], "map");
  ASSERT_EQ(m["poses"].size(), 5u);
  EXPECT_DOUBLE_EQ(m["poses"][4]["position"]["x"].get<double>(), 0.2);
  EXPECT_DOUBLE_EQ(m["poses"][4]["position"]["y"].get<double>(), 0.02);
  m = TrajectoryMessage(Map(), kT, 3);
  ASSERT_EQ(m["poses"].size(), 3u);
  EXPECT_DOUBLE_EQ(m["poses"][0]["position"]["x"].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(m["poses"][1]["position"]["x"].get<double>(), 0.1);
  EXPECT_DOUBLE_EQ(m["poses"][2]["position"]["x"].get<double>(), 0.2);
}

TEST(FoxgloveMessagesTest, LinesAreSegmentsWithCovarianceEllipses) {
  const json m = LinesMessage(Map(), kT);
  ASSERT_EQ(m["deletions"].size(), 1u);
  EXPECT_EQ(m["deletions"][0]["type"], 1);  // ALL: merged lines vanish
  ASSERT_EQ(m["entities"].size(), 2u);
  const json& e = m["entities"][0];
  EXPECT_EQ(e["id"], "line/1");
  EXPECT_EQ(e["frame_id"], "map");
  const json& seg = e["lines"][0];
  EXPECT_EQ(seg["type"], 2);
  EXPECT_DOUBLE_EQ(seg["points"][1]["x"].get<double>(), 4.0);
  const json& ell = e["lines"][1];
  EXPECT_EQ(ell["type"], 1);  // LINE_LOOP
  ASSERT_EQ(ell["points"].size(), 24u);
  // Along the line: 3 sigma_theta * half length = 3 * 0.01 * 2 = 0.06 from the centre (2, 0).
  EXPECT_NEAR(ell["points"][0]["x"].get<double>(), 2.06, 1e-12);
  EXPECT_NEAR(ell["points"][0]["y"].get<double>(), 0.0, 1e-12);
  // Across it: 3 sigma_rho = 0.06.
  EXPECT_NEAR(ell["points"][6]["x"].get<double>(), 2.0, 1e-12);
  EXPECT_NEAR(ell["points"][6]["y"].get<double>(), 0.06, 1e-12);
  // The vertical line 3: across is -x.
  const auto pts = LineEllipse(Map()["lines"][1]);
  EXPECT_NEAR(pts[6][0], 4.0 - 3 * 0.03, 1e-12);
  EXPECT_NEAR(pts[0][1], 1.5 + 3 * 0.02 * 1.5, 1e-12);
  for (const char* k : {"arrows", "cubes", "spheres", "cylinders", "triangles", "models"}) {
    EXPECT_TRUE(e[k].is_array() && e[k].empty()) << k;
  }
}

TEST(FoxgloveMessagesTest, ObjectsAreColouredByCompleteness) {
  const json m = ObjectsMessage(Map(), kT);
  ASSERT_EQ(m["entities"].size(), 2u);
  const json& done = m["entities"][0];
  EXPECT_EQ(done["id"], "object/1");
  const json& cube = done["cubes"][0];
  EXPECT_DOUBLE_EQ(cube["pose"]["position"]["x"].get<double>(), 1.25);
  EXPECT_DOUBLE_EQ(cube["pose"]["position"]["y"].get<double>(), 1.5);
  EXPECT_DOUBLE_EQ(cube["size"]["x"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(cube["size"]["y"].get<double>(), 1.0);
  EXPECT_GT(cube["color"]["g"].get<double>(), cube["color"]["r"].get<double>());  // green
  const json& open = m["entities"][1];
  EXPECT_GT(open["cubes"][0]["color"]["r"].get<double>(),
            open["cubes"][0]["color"]["g"].get<double>());  // orange
  EXPECT_EQ(open["lines"][0]["type"], 1);
  EXPECT_EQ(open["lines"][0]["points"].size(), 4u);
  EXPECT_EQ(open["texts"][0]["text"], "object 2 wall_contact (incomplete)");
}

TEST(FoxgloveMessagesTest, RoomIsTheBoxAndTheWallLines) {
  json map = Map();
  json m = RoomMessage(map, kT);
  ASSERT_EQ(m["entities"].size(), 1u);
  const json& e = m["entities"][0];
  EXPECT_EQ(e["lines"][0]["type"], 1);
  EXPECT_DOUBLE_EQ(e["lines"][0]["points"][2]["x"].get<double>(), 4.0);
  EXPECT_DOUBLE_EQ(e["lines"][0]["points"][2]["y"].get<double>(), 3.0);
  EXPECT_EQ(e["lines"][1]["points"].size(), 4u);          // walls 1 and 3
  EXPECT_EQ(e["texts"][0]["text"], "room (incomplete)");  // no top or left wall
  map["room"]["walls"]["top"] = {1};
  map["room"]["walls"]["left"] = {3};
  m = RoomMessage(map, kT);
  EXPECT_EQ(m["entities"][0]["texts"][0]["text"], "room");
  map["room"]["box"] = nullptr;
  m = RoomMessage(map, kT);
  EXPECT_TRUE(m["entities"][0]["texts"].empty());
}

// --- the server, with a Beast client on loopback -------------------------------------

namespace beast = boost::beast;
namespace websocket = beast::websocket;
using tcp = boost::asio::ip::tcp;

class FoxgloveServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ServerOptions o;
    o.max_queued_frames = 8;
    server_ = std::make_unique<Server>(io_, IrslamChannels(), o);
    std::string error;
    ASSERT_TRUE(
        server_->Listen(tcp::endpoint(boost::asio::ip::make_address("127.0.0.1"), 0), &error))
        << error;
    port_ = server_->local_endpoint().port();
  }

  // Runs the server's loop until pred holds (or 5 s).
  template <typename Pred>
  bool RunUntil(Pred pred) {
    for (int i = 0; i < 500 && !pred(); ++i) io_.run_for(std::chrono::milliseconds(10));
    return pred();
  }

  boost::asio::io_context io_;
  std::unique_ptr<Server> server_;
  unsigned short port_ = 0;
};

// A client on its own io_context, stepped by the test.
struct Client {
  explicit Client(unsigned short port, const char* subprotocol = "foxglove.websocket.v1") : ws(io) {
    beast::get_lowest_layer(ws).connect(
        tcp::endpoint(boost::asio::ip::make_address("127.0.0.1"), port));
    ws.set_option(websocket::stream_base::decorator([subprotocol](websocket::request_type& req) {
      req.set(beast::http::field::sec_websocket_protocol, subprotocol);
    }));
    ws.async_handshake(res, "127.0.0.1", "/", [this](const beast::error_code& e) {
      ec = e;
      done = true;
    });
  }
  void Read() {
    io.restart();  // run out of work after the previous operation
    done = false;
    buffer.consume(buffer.size());
    ws.async_read(buffer, [this](const beast::error_code& e, size_t) {
      ec = e;
      done = true;
    });
  }
  std::string text() const { return beast::buffers_to_string(buffer.data()); }

  boost::asio::io_context io;
  websocket::stream<beast::tcp_stream> ws;
  websocket::response_type res;
  beast::flat_buffer buffer;
  beast::error_code ec;
  bool done = false;
};

TEST_F(FoxgloveServerTest, SendsServerInfoAdvertiseThenTheLatestAndNewMessages) {
  server_->Publish(kPose, 42, R"({"latest":1})");
  Client c(port_);
  ASSERT_TRUE(RunUntil([&] {
    c.io.poll();
    return c.done;
  }));
  ASSERT_FALSE(c.ec) << c.ec.message();
  EXPECT_EQ(c.res[beast::http::field::sec_websocket_protocol], "foxglove.websocket.v1");
  c.Read();
  ASSERT_TRUE(RunUntil([&] {
    c.io.poll();
    return c.done;
  }));
  EXPECT_EQ(json::parse(c.text())["op"], "serverInfo");
  c.Read();
  ASSERT_TRUE(RunUntil([&] {
    c.io.poll();
    return c.done;
  }));
  EXPECT_EQ(json::parse(c.text())["op"], "advertise");
  c.ws.text(true);
  c.ws.write(boost::asio::buffer(
      std::string(R"({"op":"subscribe","subscriptions":[{"id":9,"channelId":2}]})")));
  c.Read();
  ASSERT_TRUE(RunUntil([&] {
    c.io.poll();
    return c.done;
  }));
  ASSERT_FALSE(c.ec);
  EXPECT_FALSE(c.ws.got_text());
  EXPECT_EQ(c.text(), MessageDataFrame(9, 42, R"({"latest":1})"));
  EXPECT_TRUE(server_->HasSubscribers(kPose));
  EXPECT_FALSE(server_->HasSubscribers(kTf));
  server_->Publish(kPose, 43, R"({"next":2})");
  server_->Publish(kTf, 43, R"({"other":3})");  // not subscribed: not sent
  c.Read();
  ASSERT_TRUE(RunUntil([&] {
    c.io.poll();
    return c.done;
  }));
  EXPECT_EQ(c.text(), MessageDataFrame(9, 43, R"({"next":2})"));
}

TEST_F(FoxgloveServerTest, ClosesAClientThatSendsBadInputAndKeepsTheOthers) {
  Client bad(port_), good(port_);
  ASSERT_TRUE(RunUntil([&] {
    bad.io.poll();
    good.io.poll();
    return bad.done && good.done;
  }));
  ASSERT_TRUE(RunUntil([&] { return server_->clients() == 2; }));
  bad.ws.text(true);
  bad.ws.write(boost::asio::buffer(std::string("{this is not json")));
  ASSERT_TRUE(RunUntil([&] { return server_->clients() == 1; }));
  EXPECT_EQ(server_->stats().bad_input, 1u);
  // The bad client reads its two greetings, then the close.
  beast::error_code ec;
  for (int i = 0; i < 3 && !ec; ++i) {
    bad.Read();
    RunUntil([&] {
      bad.io.poll();
      return bad.done;
    });
    ec = bad.ec;
  }
  EXPECT_EQ(ec, websocket::error::closed);
  EXPECT_EQ(bad.ws.reason().code, websocket::close_code::policy_error);
}

TEST_F(FoxgloveServerTest, RefusesAClientWithoutTheSubprotocol) {
  Client c(port_, "something.else");
  ASSERT_TRUE(RunUntil([&] {
    c.io.poll();
    return c.done;
  }));
  EXPECT_TRUE(c.ec);
  EXPECT_EQ(server_->stats().rejected, 1u);
}

TEST_F(FoxgloveServerTest, ASlowClientLosesMessagesAndMemoryStaysBounded) {
  Client slow(port_);
  ASSERT_TRUE(RunUntil([&] {
    slow.io.poll();
    return slow.done;
  }));
  slow.ws.text(true);
  slow.ws.write(boost::asio::buffer(
      std::string(R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":7}]})")));
  ASSERT_TRUE(RunUntil([&] { return server_->HasSubscribers(kIr); }));
  // The client reads nothing: 2000 messages of 64 KiB would be 128 MiB queued.
  const std::string big(64 * 1024, 'x');
  for (int i = 0; i < 2000; ++i) {
    server_->Publish(kIr, static_cast<uint64_t>(i), big);
    io_.poll();
  }
  // What was not dropped is in the bounded queue or the kernel's socket buffers.
  EXPECT_GT(server_->stats().dropped, 1500u);
  EXPECT_LE(server_->stats().sent, 500u);
  EXPECT_EQ(server_->clients(), 1u);  // dropped, not closed
}

}  // namespace
}  // namespace irslam::foxglove
