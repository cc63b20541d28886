// The GPIO safety logic (control/safety.h) and what RobotCore makes of it: an
// emergency stop, the bumper lines, the motor-enable output and the status LED.
#include <gtest/gtest.h>

#include "robot/robot_core.h"
#include "control/safety.h"
#include "sim/sim_run.h"

namespace irslam::control {
namespace {

TEST(DebouncerTest, PressActsAtOnceReleaseOnlyAfterStayingReleased) {
  Debouncer d(0.02);
  EXPECT_FALSE(d.Poll(0.0));
  d.Input(true, 1.000);
  EXPECT_TRUE(d.active());  // no delay on a press
  // Contact bounce: released and pressed again within the debounce time.
  d.Input(false, 1.001);
  EXPECT_TRUE(d.Poll(1.010));
  d.Input(true, 1.012);
  d.Input(false, 1.015);
  EXPECT_TRUE(d.Poll(1.030));   // 15 ms since the last release: still pressed
  EXPECT_FALSE(d.Poll(1.035));  // 20 ms: released
  EXPECT_FALSE(d.active());
}

TEST(DebouncerTest, ZeroDebounceReleasesAtTheNextPoll) {
  Debouncer d(0.0);
  d.Input(true, 1.0);
  d.Input(false, 1.0);
  EXPECT_FALSE(d.Poll(1.0));
}

TEST(LedTest, PatternPerState) {
  EXPECT_TRUE(LedOn(MissionState::kIdle, 0.3));
  EXPECT_TRUE(LedOn(MissionState::kIdle, 0.8));
  // Driving: 1 Hz.
  EXPECT_TRUE(LedOn(MissionState::kWallFollow, 10.2));
  EXPECT_FALSE(LedOn(MissionState::kWallFollow, 10.7));
  EXPECT_TRUE(LedOn(MissionState::kContourFollow, 11.4));
  // Fault: 5 Hz.
  EXPECT_TRUE(LedOn(MissionState::kFault, 3.05));
  EXPECT_FALSE(LedOn(MissionState::kFault, 3.15));
  EXPECT_TRUE(LedOn(MissionState::kFault, 3.25));
  // Done: a 0.1 s flash every 2 s.
  EXPECT_TRUE(LedOn(MissionState::kDone, 4.05));
  EXPECT_FALSE(LedOn(MissionState::kDone, 4.5));
  EXPECT_FALSE(LedOn(MissionState::kDone, 5.9));
}

sim::World LoadWorld(const std::string& name) {
  std::string error;
  auto w = sim::LoadWorldFile(std::string(IRSLAM_SOURCE_DIR) + "/tests/worlds/" + name, &error);
  EXPECT_TRUE(w) << error;
  return *w;
}

// The whole core on the simulator: an emergency stop at 10 s, released at 12 s,
// start again at 14 s; the mission carries on and still closes its loop.
TEST(EstopTest, StopsAtOnceStaysInFaultUntilReleasedAndStartedThenCarriesOn) {
  robot::CoreOptions o = robot::DefaultCoreOptions();
  bool pressed = false, released = false, restarted = false;
  double lines_at_press = 0;
  double max_speed_after = 0;
  std::string start_while_pressed, reason_after_release;
  Pose2 pose_at_press{};
  auto on_tick = [&](const sim::InProcessRun& r) {
    robot::RobotCore& core = *r.core;
    if (!pressed && r.t >= 10) {
      pressed = true;
      ASSERT_EQ(core.state(), MissionState::kWallFollow);
      ASSERT_TRUE(core.MotorEnable());
      lines_at_press = core.slam().num_lines();
      pose_at_press = r.sim->true_pose();
      core.OnSafetyInput(robot::RobotCore::SafetyInput::kEstop, true, r.t);
      // At once, before the next period: fault, enable dropped, the stop frame zero.
      EXPECT_EQ(core.state(), MissionState::kFault);
      EXPECT_FALSE(core.MotorEnable());
      EXPECT_EQ(core.last_command().left_mps, 0.0);
      EXPECT_EQ(core.Status(r.t).mission.reason, "emergency stop pressed");
      std::string why;
      EXPECT_FALSE(core.Start(r.t, &why));
      start_while_pressed = why;
      return;
    }
    if (pressed && !restarted) {
      max_speed_after = std::max({max_speed_after, std::abs(core.last_command().left_mps),
                                  std::abs(core.last_command().right_mps)});
      EXPECT_FALSE(core.MotorEnable());
      EXPECT_EQ(core.state(), MissionState::kFault);
    }
    if (pressed && !released && r.t >= 12) {
      released = true;
      core.OnSafetyInput(robot::RobotCore::SafetyInput::kEstop, false, r.t);
    }
    if (released && !restarted && r.t >= 13.9 && r.t < 14) {
      reason_after_release = core.Status(r.t).mission.reason;
      // The robot stood still all the while (the sim's wheels follow the zero command).
      EXPECT_LT(std::hypot(r.sim->true_pose().x - pose_at_press.x, r.sim->true_pose().y - pose_at_press.y), 0.05);
    }
    if (released && !restarted && r.t >= 14) {
      restarted = true;
      std::string why;
      EXPECT_TRUE(core.Start(r.t, &why)) << why;
      EXPECT_EQ(core.state(), MissionState::kWallFollow);  // resumed, not restarted
      EXPECT_GE(core.slam().num_lines(), lines_at_press);  // SLAM state kept
      EXPECT_TRUE(core.MotorEnable());
    }
  };
  sim::InProcessRun run = sim::RunInProcess(LoadWorld("wall_follow_fig14.json"), o, 1, 300, on_tick);
  ASSERT_TRUE(run.error.empty()) << run.error;
  EXPECT_TRUE(pressed && released && restarted);
  EXPECT_EQ(start_while_pressed, "emergency stop is pressed");
  EXPECT_EQ(reason_after_release, "emergency stop released: start to resume");
  EXPECT_EQ(max_speed_after, 0.0);
  EXPECT_EQ(run.core->state(), MissionState::kDone);
  EXPECT_EQ(run.sim->collisions(), 0u);
}

TEST(EstopTest, PressedWhileIdleBlocksStartUntilReleased) {
  robot::CoreOptions o = robot::DefaultCoreOptions();
  robot::RobotCore core(o);
  core.OnSafetyInput(robot::RobotCore::SafetyInput::kEstop, true, 1.0);
  EXPECT_EQ(core.state(), MissionState::kFault);
  std::string why;
  EXPECT_FALSE(core.Start(1.1, &why));
  EXPECT_EQ(why, "emergency stop is pressed");
  core.OnSafetyInput(robot::RobotCore::SafetyInput::kEstop, false, 1.2);
  core.Tick(1.21);  // 10 ms: not yet released (debounce 20 ms)
  EXPECT_TRUE(core.Status(1.21).safety.estop);
  core.Tick(1.23);
  EXPECT_FALSE(core.Status(1.23).safety.estop);
  EXPECT_TRUE(core.Status(1.23).safety.estop_latched);
  EXPECT_EQ(core.state(), MissionState::kFault);  // until start
  EXPECT_TRUE(core.StatusLed(1.25) != core.StatusLed(1.35)) << "fault blinks";
}

TEST(BumperLineTest, AGpioBumperMakesTheRobotBackOff) {
  robot::CoreOptions o = robot::DefaultCoreOptions();
  bool bumped = false;
  double min_speed_after = 1;
  std::string behaviour;
  auto on_tick = [&](const sim::InProcessRun& r) {
    robot::RobotCore& core = *r.core;
    if (!bumped && r.t >= 10) {
      bumped = true;
      core.OnSafetyInput(robot::RobotCore::SafetyInput::kBumperRight, true, r.t);
      core.OnSafetyInput(robot::RobotCore::SafetyInput::kBumperRight, false, r.t + 0.001);
      return;
    }
    if (bumped && r.t < 10.5) {
      min_speed_after = std::min(min_speed_after, core.last_command().left_mps + core.last_command().right_mps);
      if (behaviour.empty()) behaviour = ToString(core.Status(r.t).mission.behaviour);
      EXPECT_EQ(core.state(), MissionState::kWallFollow);
    }
  };
  sim::InProcessRun run = sim::RunInProcess(LoadWorld("wall_follow_fig14.json"), o, 1, 11, on_tick);
  EXPECT_TRUE(bumped);
  EXPECT_EQ(behaviour, "backoff");
  EXPECT_LT(min_speed_after, -0.05) << "the robot backs off";
}

}  // namespace
}  // namespace irslam::control
