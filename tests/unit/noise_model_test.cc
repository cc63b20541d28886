// The simulator's error envelope (issue 11, world file "noise" keys) and the
// world generator (`irslam-sim generate`): each effect measured on its own.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "proto/codec.h"
#include "robot/robot_core.h"
#include "sim/generator.h"
#include "sim/sim_run.h"

namespace irslam::sim {
namespace {

World Room(double size) {
  World w;
  w.name = "room";
  w.outline = {{0, 0}, {size, 0}, {size, size}, {0, size}};
  w.start = {size / 2, size / 2, 0};
  w.noise.slip_sigma = 0;
  w.noise.wheel_radius_error_left = w.noise.wheel_radius_error_right = 0;
  w.noise.ir_voltage_sigma_rel = 0;
  return w;
}

can_frame Cmd(double l, double r) { return proto::Encode(proto::WheelCmd{l, r, true, 0}); }

// Turns on the spot for `seconds` and returns the true heading change.
double TurnInPlace(const World& w, double seconds) {
  SimController sim(w, SimOptionsFrom(robot::DefaultCoreOptions()), 1);
  std::vector<can_frame> out;
  double turned = 0, last = sim.true_pose().theta;
  for (int i = 0; i < static_cast<int>(seconds / 0.02); ++i) {
    sim.HandleFrame(Cmd(-0.1, 0.1));
    sim.AdvanceTo(0.02 * (i + 1), &out);
    turned += NormalizeAngle(sim.true_pose().theta - last);
    last = sim.true_pose().theta;
  }
  return turned;
}

TEST(NoiseModelTest, TrackWidthErrorScalesTheTrueTurnRate) {
  World w = Room(10);
  const double nominal = TurnInPlace(w, 4);
  w.noise.wheel_base_error = 0.02;  // the true track is 2 % wider: it turns 1/1.02 as far
  EXPECT_NEAR(TurnInPlace(w, 4) / nominal, 1 / 1.02, 1e-6);
}

TEST(NoiseModelTest, CorrelatedSlipPersistsAndGrowsInTurns) {
  World w = Room(10);
  w.noise.slip_sigma = 0.02;
  w.noise.slip_correlation_s = 2.0;
  // Driving straight, the heading error from correlated slip is much larger than
  // from white slip of the same sigma (it does not average out within a step).
  const auto heading_error = [](World world) {
    SimController sim(world, SimOptionsFrom(robot::DefaultCoreOptions()), 7);
    std::vector<can_frame> out;
    for (int i = 0; i < 500; ++i) {
      sim.HandleFrame(Cmd(0.2, 0.2));
      sim.AdvanceTo(0.02 * (i + 1), &out);
    }
    return std::abs(sim.true_pose().theta);
  };
  double correlated = 0, white = 0;
  World white_world = w;
  white_world.noise.slip_correlation_s = 0;
  for (int seed = 0; seed < 8; ++seed) {
    w.seed = seed;
    correlated += heading_error(w);
    white += heading_error(white_world);
  }
  EXPECT_GT(correlated, 3 * white);
  // A turn in place scrubs more: the heading spread over seeds grows.
  EXPECT_GT(std::abs(TurnInPlace(w, 4) - TurnInPlace(Room(10), 4)), 1e-4);
}

// The IR reading of sensor 3 (straight ahead) after one sample, in metres.
std::optional<double> FrontReading(const World& w, uint64_t seed) {
  const auto core = robot::DefaultCoreOptions();
  SimController sim(w, SimOptionsFrom(core), seed);
  std::vector<can_frame> out;
  sim.AdvanceTo(0.05, &out);
  const drivers::IrCalibration cal(core.ir);
  for (const auto& f : out) {
    if (f.can_id != proto::kIrBId) continue;
    const auto b = std::get<proto::IrB>(proto::Decode(f).message);
    return cal.CountsToRange(b.adc[0]);
  }
  return std::nullopt;
}

TEST(NoiseModelTest, SurfaceBiasShiftsEveryReadingOfAFaceByTheSameAmount) {
  World w = Room(2);
  w.start = {1.5, 1.0, 0};  // 0.5 m from the right wall, looking at it
  const auto clean = FrontReading(w, 1);
  ASSERT_TRUE(clean);
  w.noise.ir_surface_bias_m = 0.04;
  std::set<long> biases;
  for (uint64_t seed = 1; seed <= 6; ++seed) {
    const auto biased = FrontReading(w, seed);
    ASSERT_TRUE(biased);
    EXPECT_LE(std::abs(*biased - *clean), 0.04 + 0.005);
    biases.insert(std::lround((*biased - *clean) * 1000));
  }
  EXPECT_GT(biases.size(), 3u);  // drawn per world (seed), not fixed
}

TEST(NoiseModelTest, GrazingReturnsDropOutBeyondTheIncidenceLimit) {
  World w = Room(4);
  w.noise.ir_beam_deg = 0;
  w.start = {1.0, 0.3, -0.35};  // sees the bottom wall ~0.83 m ahead at 70 degrees of incidence
  const auto seen = FrontReading(w, 1);
  ASSERT_TRUE(seen);
  w.noise.ir_max_incidence_deg = 60;
  EXPECT_FALSE(FrontReading(w, 1));
}

TEST(NoiseModelTest, OutliersAreTheGivenFraction) {
  World w = Room(2);
  w.start = {1.5, 1.0, 0};
  w.noise.ir_outlier_rate = 0.2;
  int outliers = 0, n = 0;
  World ref = w;
  ref.noise.ir_outlier_rate = 0;
  const auto truth = FrontReading(ref, 1);
  ASSERT_TRUE(truth);
  for (uint64_t seed = 1; seed <= 300; ++seed) {
    const auto r = FrontReading(w, seed);
    ++n;
    if (!r || std::abs(*r - *truth) > 0.02) ++outliers;
  }
  // An outlier is uniform in [0.1, 1.5] m: ~3 % of them land within 2 cm of the truth.
  EXPECT_NEAR(static_cast<double>(outliers) / n, 0.2 * (1 - 0.03), 0.07);
}

TEST(NoiseModelTest, TheDefaultsLeaveTheRandomSequenceAsItWas) {
  // A world without the new keys draws exactly what it drew before they existed:
  // the effects use their own generator.
  World a = Room(4), b = Room(4);
  a.noise = SimNoise{};
  b.noise = SimNoise{};
  b.noise.ir_surface_bias_m = 0;  // explicitly off
  EXPECT_EQ(FrontReading(a, 3), FrontReading(b, 3));
}

TEST(GeneratorTest, EveryWorldIsValidAndItsStartIsFree) {
  for (const auto profile : {NoiseProfile::kNominal, NoiseProfile::kRealistic, NoiseProfile::kHarsh}) {
    for (uint64_t seed = 1; seed <= 200; ++seed) {
      const World w = GenerateWorld(seed, profile);
      std::string error;
      const auto parsed = ParseWorld(WorldToJson(w).dump(), &error);
      ASSERT_TRUE(parsed) << ToString(profile) << " seed " << seed << ": " << error;
      const Box b = parsed->Bounds();
      EXPECT_GE(b.xmax - b.xmin, 3.0);
      EXPECT_LE(b.xmax - b.xmin, 8.0);
      EXPECT_GE(b.ymax - b.ymin, 3.0);
      EXPECT_LE(b.ymax - b.ymin, 7.0);
      EXPECT_GE(ClearanceAt(*parsed, parsed->start.x, parsed->start.y), 0.27) << seed;
      EXPECT_EQ(parsed->seed, seed);
    }
  }
}

TEST(GeneratorTest, SameSeedSameWorldAndTheKindsAllOccur) {
  EXPECT_EQ(WorldToJson(GenerateWorld(42, NoiseProfile::kRealistic)),
            WorldToJson(GenerateWorld(42, NoiseProfile::kRealistic)));
  EXPECT_NE(WorldToJson(GenerateWorld(42, NoiseProfile::kRealistic)),
            WorldToJson(GenerateWorld(43, NoiseProfile::kRealistic)));
  int legs = 0, wall_contact = 0, free = 0, empty = 0;
  for (uint64_t seed = 1; seed <= 100; ++seed) {
    const World w = GenerateWorld(seed, NoiseProfile::kNominal);
    if (w.objects.empty()) ++empty;
    for (const Box& o : w.objects) {
      if (o.xmax - o.xmin <= 0.06 && o.ymax - o.ymin <= 0.06) {
        ++legs;
      } else if (o.xmin == 0 || o.ymin == 0 || std::abs(o.xmax - w.Bounds().xmax) < 1e-9 ||
                 std::abs(o.ymax - w.Bounds().ymax) < 1e-9) {
        ++wall_contact;
      } else {
        ++free;
      }
    }
  }
  EXPECT_GT(legs, 20);
  EXPECT_GT(wall_contact, 20);
  EXPECT_GT(free, 20);
  EXPECT_GT(empty, 0);
}

TEST(GeneratorTest, ProfilesStayWithinTheirEnvelope) {
  std::mt19937_64 rng(5);
  for (int i = 0; i < 500; ++i) {
    const SimNoise r = DrawNoise(NoiseProfile::kRealistic, &rng);
    EXPECT_LE(std::abs(r.wheel_radius_error_left), 0.01);
    EXPECT_LE(std::abs(r.wheel_base_error), 0.02);
    EXPECT_LE(r.ir_voltage_sigma_rel, 0.025);
    EXPECT_GE(r.ir_max_incidence_deg, 70);
    EXPECT_LE(r.ir_outlier_rate, 0.005);
    const SimNoise h = DrawNoise(NoiseProfile::kHarsh, &rng);
    EXPECT_LE(std::abs(h.wheel_radius_error_right), 0.02);
    EXPECT_LE(h.ir_surface_bias_m, 0.04);
    EXPECT_GE(h.ir_max_incidence_deg, 60);
  }
  const SimNoise n = DrawNoise(NoiseProfile::kNominal, &rng);
  EXPECT_EQ(n.wheel_base_error, 0);
  EXPECT_EQ(n.slip_sigma, SimNoise{}.slip_sigma);
}

}  // namespace
}  // namespace irslam::sim
