// The simulator's fault injection (sim/faults.h): the SPEC grammar and what
// each fault does to the controller's frames.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "proto/codec.h"
#include "robot/robot_core.h"
#include "sim/faults.h"
#include "sim/sim_run.h"

namespace irslam::sim {
namespace {

TEST(FaultSpecTest, ParsesEveryFault) {
  std::string error;
  auto f = ParseFaultSpec(
      "loss:p=0.1,burst:every=10:len=0.2,corrupt:p=0.01,duplicate:p=0.05,reorder:p=0.02,delay:p=0.1:max=0.03,"
      "silence:at=5:for=1:reset=1,flood:at=2:for=3:rate=1000,stuck_ir:sensor=3:at=4,"
      "encoder_glitch:at=6:counts=500:wheel=both",
      &error);
  ASSERT_TRUE(f) << error;
  EXPECT_DOUBLE_EQ(f->loss_p, 0.1);
  EXPECT_DOUBLE_EQ(f->burst_len_s, 0.2);
  EXPECT_DOUBLE_EQ(f->delay_max_s, 0.03);
  ASSERT_EQ(f->silence.size(), 1u);
  EXPECT_TRUE(f->silence_reset[0]);
  EXPECT_DOUBLE_EQ(f->flood_rate, 1000);
  EXPECT_EQ(f->stuck_ir[0].sensor, 3);
  EXPECT_TRUE(f->encoder_glitch[0].left && f->encoder_glitch[0].right);
  EXPECT_TRUE(f->any());
  EXPECT_FALSE(ParseFaultSpec("", &error)->any());
}

TEST(FaultSpecTest, BadSpecsGiveOneLineNamingThePart) {
  const std::pair<const char*, const char*> cases[] = {
      {"gremlins:p=1", "faults: unknown fault 'gremlins'"},
      {"loss", "faults: 'loss': needs p="},
      {"loss:p=2", "faults: 'loss:p=2': p must be in [0, 1] (got 2)"},
      {"loss:p=x", "faults: 'loss:p=x': p must be a number"},
      {"loss:q=0.1", "faults: 'loss:q=0.1': needs p="},
      {"loss:p=0.1:q=1", "faults: 'loss:p=0.1:q=1': unknown key 'q'"},
      {"silence:at=1", "faults: 'silence:at=1': needs for="},
      {"encoder_glitch:at=1:counts=5:wheel=front", "faults: 'encoder_glitch:at=1:counts=5:wheel=front': wheel must be"},
      {"loss:0.1", "faults: 'loss:0.1': expected KEY=VALUE"},
  };
  for (const auto& [spec, want] : cases) {
    std::string error;
    EXPECT_FALSE(ParseFaultSpec(spec, &error)) << spec;
    EXPECT_EQ(error.rfind(want, 0), 0u) << spec << " -> " << error;
  }
}

TEST(FaultSpecTest, EveryFaultsKeysComeFromItsTable) {
  // Unknown keys, bounds, integers and words: the same checks and words for every fault.
  const std::pair<const char*, const char*> cases[] = {
      {"burst:every=1:len=1:width=3", "faults: 'burst:every=1:len=1:width=3': unknown key 'width'"},
      {"delay:p=0.1:min=0", "faults: 'delay:p=0.1:min=0': unknown key 'min'"},
      {"flood:at=0:for=1:id=5", "faults: 'flood:at=0:for=1:id=5': unknown key 'id'"},
      {"delay:p=0.1:max=11", "faults: 'delay:p=0.1:max=11': max must be in [0, 10] (got 11)"},
      {"silence:at=-1:for=1", "faults: 'silence:at=-1:for=1': at must be in [0, 1000000] (got -1)"},
      {"silence:at=1:for=1:reset=2", "faults: 'silence:at=1:for=1:reset=2': reset must be in [0, 1] (got 2)"},
      {"flood:at=0:for=1:rate=2e6", "faults: 'flood:at=0:for=1:rate=2e6': rate must be in [0, 1000000] (got 2000000)"},
      {"stuck_ir:sensor=7:at=1", "faults: 'stuck_ir:sensor=7:at=1': sensor must be in [0, 6] (got 7)"},
      {"stuck_ir:sensor=2.5:at=1", "faults: 'stuck_ir:sensor=2.5:at=1': sensor must be an integer"},
      {"encoder_glitch:at=1:counts=40000", "faults: 'encoder_glitch:at=1:counts=40000': counts must be in [0, 30000] (got 40000)"},
      {"encoder_glitch:at=1:counts=5:wheel=2", "faults: 'encoder_glitch:at=1:counts=5:wheel=2': wheel must be a string"},
      {"corrupt:p=nan", "faults: 'corrupt:p=nan': p must be a number"},
  };
  for (const auto& [spec, want] : cases) {
    std::string error;
    EXPECT_FALSE(ParseFaultSpec(spec, &error)) << spec;
    EXPECT_EQ(error, want) << spec;
  }
  // Defaults of keys not given, and a flood without rate= keeps an earlier one's.
  std::string error;
  auto f = ParseFaultSpec("delay:p=0.5,stuck_ir:sensor=6:at=1,flood:at=0:for=1:rate=100,flood:at=5:for=1",
                          &error);
  ASSERT_TRUE(f) << error;
  EXPECT_DOUBLE_EQ(f->delay_max_s, 0.02);
  EXPECT_EQ(f->stuck_ir[0].sensor, 6);
  EXPECT_DOUBLE_EQ(f->stuck_ir[0].when.len, 1e9);
  EXPECT_EQ(f->flood.size(), 2u);
  EXPECT_DOUBLE_EQ(f->flood_rate, 100);
}

std::vector<can_frame> Enc(uint16_t stamp, uint16_t l, uint16_t r, uint8_t seq) {
  return {proto::Encode(proto::EncoderCounts{stamp, l, r, seq})};
}

proto::EncoderCounts AsEnc(const can_frame& f) { return std::get<proto::EncoderCounts>(proto::Decode(f).message); }

TEST(FaultInjectorTest, SilenceWithResetRestartsClockCountsAndSequences) {
  std::string error;
  FaultInjector inj(*ParseFaultSpec("silence:at=1:for=0.5:reset=1", &error), 1);
  std::vector<can_frame> out;
  inj.Process(0.99, Enc(990, 1000, 2000, 99), &out);
  inj.Process(1.2, Enc(1200, 1040, 2040, 120), &out);  // silent
  ASSERT_EQ(out.size(), 1u);
  inj.Process(1.6, Enc(1600, 1120, 2120, 160), &out);
  inj.Process(1.61, Enc(1610, 1122, 2122, 161), &out);
  ASSERT_EQ(out.size(), 3u);
  const auto a = AsEnc(out[1]), b = AsEnc(out[2]);
  EXPECT_EQ(a.timestamp_ms, 5);
  EXPECT_EQ(a.left, 0);
  EXPECT_EQ(a.seq, 0);
  EXPECT_EQ(b.timestamp_ms, 15);
  EXPECT_EQ(b.left, 2);
  EXPECT_EQ(b.right, 2);
  EXPECT_EQ(b.seq, 1);
  EXPECT_EQ(inj.counters().silenced, 1u);
}

TEST(FaultInjectorTest, GlitchStuckSensorAndFlood) {
  std::string error;
  FaultInjector inj(*ParseFaultSpec("encoder_glitch:at=1:counts=5000,stuck_ir:sensor=4:at=1:for=1,flood:at=0:for=1:rate=1000",
                                    &error),
                    1);
  std::vector<can_frame> out;
  inj.Process(0.5, Enc(500, 100, 100, 1), &out);
  inj.Process(1.0, Enc(1000, 110, 110, 2), &out);
  EXPECT_EQ(AsEnc(out[0]).left, 100);
  EXPECT_EQ(AsEnc(out[1]).left, 5110);  // the jump stays
  EXPECT_EQ(AsEnc(out[1]).right, 110);
  out.clear();
  inj.Process(1.1, {proto::Encode(proto::IrB{1, {10, 20, 30, 40}})}, &out);
  inj.Process(1.2, {proto::Encode(proto::IrB{2, {11, 21, 31, 41}})}, &out);
  inj.Process(2.2, {proto::Encode(proto::IrB{3, {12, 22, 32, 42}})}, &out);
  const auto ir = [&](size_t i) { return std::get<proto::IrB>(proto::Decode(out[i]).message).adc; };
  EXPECT_EQ(ir(1)[1], 20);  // sensor 4 = IR_B's second value: stuck at 20
  EXPECT_EQ(ir(1)[0], 11);
  EXPECT_EQ(ir(2)[1], 22);  // the window is over
  out.clear();
  inj.Flood(0.5, 0.01, &out);  // 10 ms of wall time at 1000 frames/s
  ASSERT_EQ(out.size(), 10u);
  for (const auto& f : out) EXPECT_GE(f.can_id, 0x200u);
  out.clear();
  inj.Flood(1.5, 0.01, &out);
  EXPECT_TRUE(out.empty());
}

TEST(FaultInjectorTest, LossDuplicateReorderAndDelayAtTheirRates) {
  std::string error;
  FaultInjector inj(*ParseFaultSpec("loss:p=0.1,duplicate:p=0.1,reorder:p=0.1,delay:p=0.1:max=0.05", &error), 7);
  std::vector<can_frame> out;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    inj.Process(i * 0.01, Enc(static_cast<uint16_t>(i * 10), 0, 0, static_cast<uint8_t>(i)), &out);
  }
  const auto& c = inj.counters();
  EXPECT_NEAR(c.lost, 0.1 * n, 0.01 * n);
  EXPECT_GT(c.duplicated, 0.05 * n);
  EXPECT_GT(c.reordered, 0.05 * n);
  EXPECT_GT(c.delayed, 0.05 * n);
  inj.Process(n * 0.01 + 1, {}, &out);  // the delayed ones come out
  // Everything not lost arrives (duplicates twice; one may still wait to be swapped).
  EXPECT_LE(out.size(), n - c.lost + c.duplicated);
  EXPECT_GE(out.size() + 1, n - c.lost + c.duplicated);
  int out_of_order = 0;
  for (size_t i = 1; i < out.size(); ++i) out_of_order += AsEnc(out[i]).timestamp_ms < AsEnc(out[i - 1]).timestamp_ms;
  EXPECT_GT(out_of_order, 0.05 * n);
}

}  // namespace
}  // namespace irslam::sim

namespace irslam::sim {
namespace {

TEST(FaultSpecTest, KidnapIsParsedFromItsTableInTimeOrder) {
  std::string error;
  auto f = ParseFaultSpec("kidnap:at=60:x=1.5:y=2:theta=4,kidnap:at=30:x=3:y=1", &error);
  ASSERT_TRUE(f) << error;
  EXPECT_TRUE(f->any());
  ASSERT_EQ(f->kidnap.size(), 2u);
  EXPECT_DOUBLE_EQ(f->kidnap[0].at, 30);
  EXPECT_DOUBLE_EQ(f->kidnap[0].to.x, 3);
  EXPECT_DOUBLE_EQ(f->kidnap[0].to.theta, 0);
  EXPECT_DOUBLE_EQ(f->kidnap[1].to.theta, 4 - 2 * M_PI);  // normalised
  const std::pair<const char*, const char*> cases[] = {
      {"kidnap:at=1:x=2", "faults: 'kidnap:at=1:x=2': needs y="},
      {"kidnap:x=1:y=2", "faults: 'kidnap:x=1:y=2': needs at="},
      {"kidnap:at=1:x=2:y=3:z=0", "faults: 'kidnap:at=1:x=2:y=3:z=0': unknown key 'z'"},
      {"kidnap:at=1:x=2e4:y=3", "faults: 'kidnap:at=1:x=2e4:y=3': x must be in [-1000, 1000] (got 20000)"},
      {"kidnap:at=1:x=2:y=a", "faults: 'kidnap:at=1:x=2:y=a': y must be a number"},
  };
  for (const auto& [spec, want] : cases) {
    EXPECT_FALSE(ParseFaultSpec(spec, &error)) << spec;
    EXPECT_EQ(error, want) << spec;
  }
}

TEST(FaultInjectorTest, EachKidnapIsTakenOnceWhenItsTimeComes) {
  std::string error;
  FaultInjector inj(*ParseFaultSpec("kidnap:at=2:x=1:y=1,kidnap:at=2.5:x=2:y=2:theta=1", &error), 1);
  EXPECT_FALSE(inj.TakeKidnap(1.99));
  const auto first = inj.TakeKidnap(2.0);
  ASSERT_TRUE(first);
  EXPECT_DOUBLE_EQ(first->x, 1);
  EXPECT_FALSE(inj.TakeKidnap(2.1));
  const auto second = inj.TakeKidnap(9);
  ASSERT_TRUE(second);
  EXPECT_DOUBLE_EQ(second->theta, 1);
  EXPECT_FALSE(inj.TakeKidnap(10));
  EXPECT_EQ(inj.counters().kidnapped, 2u);
}

// In a whole in-process run: after the kidnap time the true pose is the target
// (give or take what the robot drove since), and the encoders never jump: the
// counts per 10 ms frame stay what the wheels' top speed allows.
TEST(KidnapTest, TheTruePoseJumpsAndTheEncodersDoNot) {
  std::string error;
  auto world = LoadWorldFile(std::string(IRSLAM_SOURCE_DIR) + "/tests/worlds/fig14.json", &error);
  ASSERT_TRUE(world) << error;
  auto faults = ParseFaultSpec("kidnap:at=8:x=3.2:y=4.8:theta=-2", &error);
  ASSERT_TRUE(faults) << error;
  const robot::CoreOptions o = robot::DefaultCoreOptions();
  const double max_counts_per_frame =
      o.slam.geometry.max_wheel_speed_mps * 0.010 / o.slam.geometry.metres_per_count() + 2;
  Pose2 before_jump, after_jump;
  bool seen_before = false, seen_after = false;
  const auto on_tick = [&](const InProcessRun& r) {
    if (r.t < 8 - 1e-9) before_jump = r.sim->true_pose(), seen_before = true;
    if (!seen_after && r.t >= 8 + 1e-9) after_jump = r.sim->true_pose(), seen_after = true;
  };
  const InProcessRun run = RunInProcess(*world, o, 1, 8.5, on_tick, &*faults);
  ASSERT_TRUE(run.error.empty()) << run.error;
  ASSERT_TRUE(seen_before && seen_after);
  EXPECT_EQ(run.faults->counters().kidnapped, 1u);
  EXPECT_GT(std::hypot(before_jump.x - 3.2, before_jump.y - 4.8), 1.0);
  EXPECT_NEAR(after_jump.x, 3.2, 0.02);
  EXPECT_NEAR(after_jump.y, 4.8, 0.02);
  EXPECT_NEAR(after_jump.theta, -2, 0.05);
  // The truth file: the true trajectory jumps once, dead reckoning never.
  const nlohmann::json truth = run.sim->Truth();
  double true_jump = 0, odom_jump = 0;
  for (size_t i = 1; i < truth["trajectory"].size(); ++i) {
    const auto &a = truth["trajectory"][i - 1], &b = truth["trajectory"][i];
    true_jump = std::max(true_jump, std::hypot(b[1].get<double>() - a[1].get<double>(),
                                               b[2].get<double>() - a[2].get<double>()));
    const auto &c = truth["odometry"][i - 1], &d = truth["odometry"][i];
    odom_jump = std::max(odom_jump, std::hypot(d[1].get<double>() - c[1].get<double>(),
                                               d[2].get<double>() - c[2].get<double>()));
  }
  EXPECT_GT(true_jump, 1.0);
  EXPECT_LT(odom_jump, 0.05);  // 50 ms at most 0.5 m/s
  // The encoder frames themselves: a simulator driven straight at 0.3 m/s,
  // kidnapped at 2 s. Per 10 ms frame the counts move by what the wheels turn.
  SimController sim(*world, SimOptionsFrom(o), 1);
  FaultInjector inj(*ParseFaultSpec("kidnap:at=2:x=1:y=4.8:theta=0", &error), 1);
  std::vector<can_frame> frames;
  std::optional<proto::EncoderCounts> last;
  int64_t max_step = 0, total = 0;
  for (int i = 1; i <= 2000; ++i) {  // 4 s
    const double t = 0.002 * i;
    if (i % 10 == 0) sim.HandleFrame(proto::Encode(proto::WheelCmd{{0.3, 0.3, true}, 0}));
    while (const auto to = inj.TakeKidnap(t)) sim.Teleport(*to);
    frames.clear();
    sim.AdvanceTo(t, &frames);
    for (const can_frame& f : frames) {
      const auto d = proto::Decode(f);
      if (const auto* e = std::get_if<proto::EncoderCounts>(&d.message)) {
        if (last) {
          const int64_t step = static_cast<int16_t>(static_cast<uint16_t>(e->left - last->left));
          max_step = std::max(max_step, std::abs(step));
          total += step;
        }
        last = *e;
      }
    }
  }
  EXPECT_NEAR(sim.true_pose().x, 1 + 2 * 0.3 - 0.03, 0.05);  // driven on from the target (from standstill)
  EXPECT_NEAR(sim.true_pose().y, 4.8, 0.05);
  EXPECT_GT(total, 0);
  EXPECT_LE(static_cast<double>(max_step), max_counts_per_frame);
}

}  // namespace
}  // namespace irslam::sim
