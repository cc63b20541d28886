#include <gtest/gtest.h>

#include <cstring>

#include "robot/robot_core.h"
#include "proto/codec.h"
#include "sim/sim_run.h"

namespace irslam::sim {
namespace {

World OpenRoom(double slip, double mismatch) {
  World w;
  w.name = "open";
  w.outline = {{0, 0}, {20, 0}, {20, 20}, {0, 20}};
  w.start = {10, 10, 0};
  w.noise.slip_sigma = slip;
  w.noise.wheel_radius_error_left = mismatch;
  w.noise.wheel_radius_error_right = -mismatch;
  return w;
}

can_frame Cmd(double l, double r) { return proto::Encode(proto::WheelCmd{{l, r, true}, 0}); }

TEST(SimControllerTest, DrivesStraightAndEncodesCounts) {
  const auto core = robot::DefaultCoreOptions();
  SimController sim(OpenRoom(0, 0), SimOptionsFrom(core), 1);
  std::vector<can_frame> out;
  for (int i = 0; i < 100; ++i) {  // 2 s, commands every 20 ms
    sim.HandleFrame(Cmd(0.2, 0.2));
    sim.AdvanceTo(0.02 * (i + 1), &out);
  }
  // Accelerates at 1.5 m/s^2 to 0.2 m/s: 0.2*2 - 0.2^2/(2*1.5) = 0.3867 m.
  EXPECT_NEAR(sim.true_pose().x - 10, 0.3867, 0.002);
  EXPECT_NEAR(sim.true_pose().y, 10, 1e-9);
  EXPECT_NEAR(sim.odometry_pose().x, sim.true_pose().x, 0.001);
  int enc = 0, ir = 0, status = 0;
  for (const auto& f : out) {
    enc += f.can_id == proto::kEncoderId;
    ir += f.can_id == proto::kIrAId;
    status += f.can_id == proto::kControllerStatusId;
  }
  EXPECT_EQ(enc, 200);                // 100 Hz
  EXPECT_EQ(status, 40);              // 20 Hz
  EXPECT_NEAR(ir, 2.0 / 0.038, 3);    // ~26 Hz
}

TEST(SimControllerTest, StopsTheWheelsWhenCommandsStopFor200ms) {
  const auto core = robot::DefaultCoreOptions();
  SimController sim(OpenRoom(0, 0), SimOptionsFrom(core), 1);
  std::vector<can_frame> out;
  sim.HandleFrame(Cmd(0.3, 0.3));
  sim.AdvanceTo(0.19, &out);
  EXPECT_GT(sim.wheel_speed_left(), 0.25);
  sim.AdvanceTo(0.6, &out);
  EXPECT_DOUBLE_EQ(sim.wheel_speed_left(), 0.0);
  const auto st = std::get<proto::ControllerStatus>(proto::Decode(
      [&] { for (auto it = out.rbegin(); it != out.rend(); ++it) if (it->can_id == proto::kControllerStatusId) return *it; return can_frame{}; }()).message);
  EXPECT_TRUE(st.faults & proto::kFaultCommandTimeout);
}

TEST(SimControllerTest, CollisionStopsTheRobotAndSetsABumper) {
  auto core = robot::DefaultCoreOptions();
  World w = OpenRoom(0, 0);
  w.objects.push_back({11.0, 9.0, 12.0, 11.0});
  SimController sim(w, SimOptionsFrom(core), 1);
  std::vector<can_frame> out;
  for (int i = 0; i < 400; ++i) {
    sim.HandleFrame(Cmd(0.3, 0.3));
    sim.AdvanceTo(0.02 * (i + 1), &out);
  }
  EXPECT_NEAR(sim.true_pose().x, 11.0 - core.slam.geometry.radius_m, 0.01);
  EXPECT_EQ(sim.collisions(), 1u);
  EXPECT_EQ(sim.bumpers(), kBumperLeft | kBumperRight);
}

TEST(SimControllerTest, SameSeedSameRun) {
  const auto core = robot::DefaultCoreOptions();
  SimController a(OpenRoom(0.02, 0.001), SimOptionsFrom(core), 7);
  SimController b(OpenRoom(0.02, 0.001), SimOptionsFrom(core), 7);
  SimController c(OpenRoom(0.02, 0.001), SimOptionsFrom(core), 8);
  std::vector<can_frame> fa, fb, fc;
  for (int i = 0; i < 200; ++i) {
    for (auto* s : {&a, &b, &c}) s->HandleFrame(Cmd(0.2, 0.25));
    a.AdvanceTo(0.02 * (i + 1), &fa);
    b.AdvanceTo(0.02 * (i + 1), &fb);
    c.AdvanceTo(0.02 * (i + 1), &fc);
  }
  EXPECT_EQ(a.true_pose().x, b.true_pose().x);
  ASSERT_EQ(fa.size(), fb.size());
  EXPECT_EQ(0, std::memcmp(fa.data(), fb.data(), fa.size() * sizeof(can_frame)));
  EXPECT_NE(a.true_pose().x, c.true_pose().x);
}

TEST(SimControllerTest, WheelRadiusMismatchMakesOdometryDrift) {
  const auto core = robot::DefaultCoreOptions();
  SimController sim(OpenRoom(0, 0.002), SimOptionsFrom(core), 1);
  std::vector<can_frame> out;
  for (int i = 0; i < 1000; ++i) {
    sim.HandleFrame(Cmd(0.3, 0.3));
    sim.AdvanceTo(0.02 * (i + 1), &out);
  }
  // Odometry believes it went straight; the true path curved right.
  EXPECT_NEAR(sim.odometry_pose().theta, 0.0, 1e-9);
  EXPECT_LT(sim.true_pose().theta, -0.05);
}

TEST(SimControllerTest, IrSensorsSeeTheWallAtTheRightDistance) {
  const auto core = robot::DefaultCoreOptions();
  World w = OpenRoom(0, 0);
  w.noise.ir_voltage_sigma_rel = 0;
  w.objects.push_back({10.6, 5, 11, 15});  // a wall 0.6 m ahead of the centre
  SimController sim(w, SimOptionsFrom(core), 1);
  std::vector<can_frame> out;
  sim.AdvanceTo(0.05, &out);
  robot::RobotCore rc(core);
  for (const auto& f : out) rc.OnFrame(f, 0.05);
  const auto ranges = rc.Status(0.05).ir.scan.range_m;
  ASSERT_TRUE(ranges[3]);
  EXPECT_NEAR(*ranges[3], 0.55, 0.003);  // sensor sits 5 cm ahead of the centre
  EXPECT_FALSE(ranges[0]);               // nothing on the right
}

}  // namespace
}  // namespace irslam::sim
