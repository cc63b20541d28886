// The map as a ROS map_server occupancy grid (daemon/map_pgm.h).
#include "daemon/map_pgm.h"

#include <gtest/gtest.h>

namespace irslam {
namespace {

nlohmann::json Line(double x0, double y0, double x1, double y1) {
  return {{"p0", {x0, y0}}, {"p1", {x1, y1}}};
}

// A 4 x 3 m room with its four walls and a 1 x 1 m box standing free at (2, 1).
nlohmann::json TestMap() {
  nlohmann::json lines = {Line(0, 0, 4, 0), Line(4, 0, 4, 3), Line(4, 3, 0, 3), Line(0, 3, 0, 0),
                          Line(2, 1, 3, 1), Line(3, 1, 3, 2), Line(3, 2, 2, 2), Line(2, 2, 2, 1)};
  return {{"frame", "map"},
          {"lines", lines},
          {"room", {{"box", {0, 0, 4, 3}}}},
          {"objects", {{{"id", 1}, {"kind", "free"}, {"box", {2, 1, 3, 2}}}}}};
}

// The cell of map point (x, y).
uint8_t At(const PgmImage& img, double x, double y) {
  const int col = static_cast<int>((x - img.origin_x) / img.resolution_m);
  const int row = img.height - 1 - static_cast<int>((y - img.origin_y) / img.resolution_m);
  return img.at(col, row);
}

TEST(MapPgmTest, WallsAndSidesOccupiedRoomFreeOutsideAndFurnitureUnknown) {
  std::string error;
  const auto img = RenderPgm(TestMap(), 0.05, &error);
  ASSERT_TRUE(img) << error;
  // 0.25 m of margin on each side, on the 5 cm grid: 4.5 x 3.5 m.
  EXPECT_DOUBLE_EQ(img->origin_x, -0.25);
  EXPECT_DOUBLE_EQ(img->origin_y, -0.25);
  EXPECT_EQ(img->width, 90);
  EXPECT_EQ(img->height, 70);
  EXPECT_EQ(At(*img, 1.0, 1.5), kPgmFree);       // inside the room
  EXPECT_EQ(At(*img, 1.0, 0.01), kPgmOccupied);  // the bottom wall
  EXPECT_EQ(At(*img, 4.01, 1.5), kPgmOccupied);  // the right wall (x = 4 is in the cell [4, 4.05))
  EXPECT_EQ(At(*img, 2.5, 1.01), kPgmOccupied);  // the box's bottom side
  EXPECT_EQ(At(*img, 2.5, 1.5), kPgmUnknown);    // inside the box
  EXPECT_EQ(At(*img, -0.2, 1.5), kPgmUnknown);   // outside the room
  // Top-left pixel is outside (row 0 is the top: y = 3.25).
  EXPECT_EQ(img->at(0, 0), kPgmUnknown);
  int occupied = 0, free_cells = 0;
  for (uint8_t c : img->cells) {
    occupied += c == kPgmOccupied;
    free_cells += c == kPgmFree;
  }
  // Walls: 2 x (80 + 60) cells plus the corners' neighbours; the box: 4 x 20.
  EXPECT_GE(occupied, 2 * (80 + 60) + 4 * 20 - 8);
  EXPECT_LE(occupied, 2 * (80 + 60) + 4 * 20 + 8);
  // The room (80 x 60 cells) less the box (20 x 20) and the lines drawn on free cells:
  // a line on x = a is in the cell [a, a + 5 cm), so the bottom and left walls
  // (80 + 60 - 1 at the corner) and the box's right and top sides (20 + 20 + 1).
  EXPECT_EQ(free_cells, 80 * 60 - 20 * 20 - (80 + 60 - 1) - (20 + 20 + 1));
}

TEST(MapPgmTest, EncodesBinaryPgmAndMapServerYaml) {
  std::string error;
  const auto img = RenderPgm(TestMap(), 0.1, &error);
  ASSERT_TRUE(img) << error;
  const std::string pgm = EncodePgm(*img);
  // The origin on the 10 cm grid (-0.3), the far side 0.25 m beyond the room: 46 x 36.
  const std::string head = "P5\n# irslam map (map frame), 0.100000 m/cell\n46 36\n255\n";
  ASSERT_EQ(pgm.substr(0, head.size()), head);
  EXPECT_EQ(pgm.size(), head.size() + 46u * 36u);
  EXPECT_EQ(MapServerYaml(*img, "map.pgm"),
            "image: map.pgm\nresolution: 0.1\norigin: [-0.300000, -0.300000, 0.0]\nnegate: 0\n"
            "occupied_thresh: 0.65\nfree_thresh: 0.196\n");
  EXPECT_EQ(PgmYamlPath("out/map.pgm"), "out/map.yaml");
  EXPECT_EQ(PgmYamlPath("grid"), "grid.yaml");
}

TEST(MapPgmTest, RefusesMapsItCannotDraw) {
  std::string error;
  EXPECT_FALSE(RenderPgm(nlohmann::json::object(), 0.05, &error));
  EXPECT_EQ(error, "the map has no \"lines\" array");
  EXPECT_FALSE(RenderPgm({{"lines", nlohmann::json::array()}}, 0.05, &error));
  EXPECT_EQ(error, "the map has neither lines nor a room");
  EXPECT_FALSE(RenderPgm({{"lines", {Line(0, 0, 500, 0)}}}, 0.05, &error));
  EXPECT_EQ(error, "the map is larger than 200 m a side");
  EXPECT_FALSE(RenderPgm({{"lines", {{{"p0", {0, 0}}}}}}, 0.05, &error));
  EXPECT_EQ(error, "a line without p0 and p1");
  EXPECT_FALSE(RenderPgm(TestMap(), 0, &error));
}

}  // namespace
}  // namespace irslam
