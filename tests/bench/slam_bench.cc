// Google Benchmark targets for the SLAM core (results: docs/benchmarks.md).
#include <benchmark/benchmark.h>

#include <chrono>
#include <random>

#include "robot/robot_core.h"
#include "slam/line_ekf.h"
#include "slam/line_extraction.h"
#include "slam/slam.h"
#include "sim/sim_run.h"

namespace irslam::slam {
namespace {

// A 100-point PDS: two walls of a corner seen from the robot, with noise.
Points CornerPds(uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0, 0.004);
  Points p;
  for (int i = 0; i < 55; ++i) p.emplace_back(-0.2 + 0.02 * i, -0.4 + n(rng));
  for (int i = 0; i < 45; ++i) p.emplace_back(0.9 + n(rng), -0.38 + 0.02 * i);
  return p;
}

void BM_ExtractLines100(benchmark::State& state) {
  const Points pds = CornerPds(1);
  const ExtractionOptions o;
  size_t lines = 0;
  for (auto _ : state) {
    auto l = ExtractLines(pds, {0, 0}, o);
    lines = l.size();
    benchmark::DoNotOptimize(l);
  }
  state.counters["lines"] = static_cast<double>(lines);
}
BENCHMARK(BM_ExtractLines100);

// The paper's Table 1: the constrained transform (11 x 11 cells around the LS fit)
// against the full one (360 x 180 cells) on the same cluster.
Points Wall(uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0, 0.004);
  Points p;
  for (int i = 0; i < 50; ++i) p.emplace_back(-0.2 + 0.02 * i, -0.4 + n(rng));
  return p;
}

void BM_ConstrainedHough(benchmark::State& state) {
  const Points p = Wall(2);
  const ExtractionOptions o;
  const LineFit f = FitLine(p);
  HoughResult h;
  for (auto _ : state) {
    h = ConstrainedHough(p, f.rho, f.theta, o);
    benchmark::DoNotOptimize(h);
  }
  state.counters["cells"] = h.cells;
  state.counters["votes"] = h.votes_cast;
}
BENCHMARK(BM_ConstrainedHough);

void BM_FullHough(benchmark::State& state) {
  const Points p = Wall(2);
  const ExtractionOptions o;
  HoughResult h;
  for (auto _ : state) {
    h = FullHough(p, 1.79, o);
    benchmark::DoNotOptimize(h);
  }
  state.counters["cells"] = h.cells;
  state.counters["votes"] = h.votes_cast;
}
BENCHMARK(BM_FullHough);

// One EKF measurement update (eq. 10 + the eq. 11 constraint row) with N lines.
void BM_EkfUpdate(benchmark::State& state) {
  const int n_lines = static_cast<int>(state.range(0));
  LineEkf ekf;
  Eigen::Matrix2d r = Eigen::Matrix2d::Identity() * 1e-4;
  for (int i = 0; i < n_lines; ++i) ekf.AddLine({0.5 + 0.1 * i, (i % 4) * M_PI / 2 - M_PI / 2 + 0.01}, r);
  ekf.Predict({0.5, 0.1}, MotionNoise{});
  const long n = ekf.x().size();
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(3, n);
  const int k = n_lines / 2;
  Eigen::Matrix<double, 2, 5> j;
  PredictObservation(ekf.pose(), ekf.rho(k), ekf.theta(k), &j);
  for (int row = 0; row < 2; ++row) {
    h.row(row).head<3>() = j.row(row).head<3>();
    h(row, LineEkf::RhoIndex(k)) = j(row, 3);
    h(row, LineEkf::ThetaIndex(k)) = j(row, 4);
  }
  h(2, LineEkf::ThetaIndex(k)) = 1;
  h(2, LineEkf::ThetaIndex(0)) = -1;
  Eigen::MatrixXd rr = Eigen::MatrixXd::Zero(3, 3);
  rr.topLeftCorner<2, 2>() = r;
  rr(2, 2) = 1e-6;
  const Eigen::VectorXd y = Eigen::VectorXd::Constant(3, 1e-4);
  const Eigen::VectorXd x0 = ekf.x();
  const Eigen::MatrixXd p0 = ekf.P();
  for (auto _ : state) {
    ekf.Update(y, h, rr);
    state.PauseTiming();
    ekf.mutable_x() = x0;
    ekf.SetCovariance(p0);
    state.ResumeTiming();
  }
  state.counters["state_dim"] = static_cast<double>(n);
}
BENCHMARK(BM_EkfUpdate)->Arg(10)->Arg(50)->Arg(100)->Arg(200);

// A whole wall-following mission of the Fig. 14 room in process: robot seconds
// simulated per wall second.
void BM_MissionFig14(benchmark::State& state) {
  std::string error;
  auto world = sim::LoadWorldFile(std::string(IRSLAM_SOURCE_DIR) + "/tests/worlds/fig14.json", &error);
  if (!world) {
    state.SkipWithError(error.c_str());
    return;
  }
  double robot_s = 0, wall_s = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    auto run = sim::RunInProcess(*world, robot::DefaultCoreOptions(), 1, 600);
    wall_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    robot_s += run.t;
    benchmark::DoNotOptimize(run);
  }
  state.counters["robot_s"] = robot_s / static_cast<double>(state.iterations());
  state.counters["x_realtime"] = robot_s / wall_s;
}
BENCHMARK(BM_MissionFig14)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace irslam::slam

BENCHMARK_MAIN();
