#include <gtest/gtest.h>

#include "sim/world.h"

namespace irslam::sim {
namespace {

TEST(WorldTest, ParsesTheContractExample) {
  std::string error;
  auto w = ParseWorld(R"({"name": "paper-fig14", "room": [4.0, 5.5],
      "objects": [[0.0, 2.0, 0.6, 3.2], [1.4, 1.2, 2.2, 1.8]], "start": [2.0, 0.8, 1.0]})", &error);
  ASSERT_TRUE(w) << error;
  EXPECT_EQ(w->name, "paper-fig14");
  EXPECT_EQ(w->outline.size(), 4u);
  EXPECT_EQ(w->objects.size(), 2u);
  EXPECT_DOUBLE_EQ(w->start.theta, 1.0);
  EXPECT_EQ(w->Segments().size(), 4u + 8u);
}

TEST(WorldTest, HonoursSeedNoiseAndOutline) {
  std::string error;
  auto w = ParseWorld(R"({"outline": [[0,0],[3,0],[3,2],[2,2],[2,3],[0,3]],
      "start": [1, 1, 0], "seed": 42, "noise": {"slip_sigma": 0.0}})", &error);
  ASSERT_TRUE(w) << error;
  EXPECT_EQ(*w->seed, 42u);
  EXPECT_DOUBLE_EQ(w->noise.slip_sigma, 0.0);
  EXPECT_EQ(w->outline.size(), 6u);
}

TEST(WorldTest, MalformedFilesNameTheField) {
  const std::pair<const char*, const char*> cases[] = {
      {"{", "not valid JSON"},
      {R"({"start": [1,1,0]})", "\"room\""},
      {R"({"room": [4], "start": [1,1,0]})", "\"room\""},
      {R"({"room": [4,4], "start": [1,1]})", "\"start\""},
      {R"({"room": [4,4], "start": [9,1,0]})", "outside the room"},
      {R"({"room": [4,4], "start": [1,1,0], "objects": [[1,1,0,2]]})", "\"objects\"[0]"},
      {R"({"room": [4,4], "start": [1,1,0], "seed": "x"})", "\"seed\""},
      {R"({"room": [4,4], "start": [1,1,0], "noise": {"slip_sigma": -1}})", "noise.slip_sigma"},
      {R"({"outline": [[0,0],[3,1],[3,3],[0,3]], "start": [1,1,0]})", "not axis-aligned"},
      // Issue 12 / contracts §1 (2026-12): unknown keys are rejected by name, and
      // impossible worlds are errors (a typo such as "objcts" gave an empty room).
      {R"({"room": [4,4], "start": [1,1,0], "objcts": [[2,2,3,3]]})", "\"objcts\" is not a known key"},
      {R"({"room": [4,4], "start": [1,1,0], "noise": {"slip": 0.1}})", "noise.slip is not a known key"},
      // fuzz_world (2026-12-02): a key with an escaped newline came back as a
      // two-line error; control characters are now written as escapes.
      {R"({"u\nobj2,1,2<2]],bmeo&uE7Ea":0})", R"("u\nobj2,1,2<2]],bmeo&uE7Ea" is not a known key)"},
      {R"({"room": [4,4], "start": [1,1,0], "noise": {"a\u0007\tb": 1}})", R"(noise.a\u0007\tb is not a known key)"},
      {R"({"room": [4,4], "start": [1,1,0], "objects": [[3,3,5,5]]})", "\"objects\"[0] lies outside the room"},
      {R"({"room": [4,4], "start": [2.5,2.5,0], "objects": [[2,2,3,3]]})", "\"start\" lies inside \"objects\"[0]"},
      {R"({"outline": [[0,0],[3,0],[3,2],[2,2],[2,3],[0,3]], "start": [1,1,0], "objects": [[2.2,2.2,2.8,2.8]]})",
       "\"objects\"[0] lies outside the room"},
  };
  for (const auto& [text, field] : cases) {
    std::string error;
    EXPECT_FALSE(ParseWorld(text, &error)) << text;
    EXPECT_NE(error.find(field), std::string::npos) << text << " -> " << error;
    EXPECT_EQ(error.find('\n'), std::string::npos);
  }
}

TEST(RayCastTest, HitsTheNearestSegment) {
  const std::vector<Segment> segs = {{{2, -1}, {2, 1}}, {{3, -1}, {3, 1}}};
  EXPECT_NEAR(*RayCast(segs, {0, 0}, 0, 10), 2.0, 1e-12);
  EXPECT_NEAR(*RayCast(segs, {0, 0}, std::atan2(0.5, 2), 10), std::hypot(2, 0.5), 1e-12);
  EXPECT_FALSE(RayCast(segs, {0, 0}, M_PI, 10));
  EXPECT_FALSE(RayCast(segs, {0, 0}, 0, 1.5));
}

}  // namespace
}  // namespace irslam::sim
