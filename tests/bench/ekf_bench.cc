// Google Benchmark: one EKF measurement update with N map lines, the in-place
// update (LineEkf::Update) beside the former dense one (LineEkf::UpdateReference)
// in the same run. Results: docs/benchmarks.md, "EKF update".
//
// The update is a matched observation as Slam makes it: eq. (10) (2 rows on the
// pose and the observed line) plus the eq. (11) row tying the line's angle to the
// first wall's, m = 3. The state is not reset between iterations (the cost does
// not depend on the values; a reset would cost more than the update): the zero
// innovation leaves x unchanged and only shrinks P a little each time.
#include <benchmark/benchmark.h>

#include <cmath>

#include "slam/line_ekf.h"

namespace irslam::slam {
namespace {

struct Problem {
  LineEkf ekf;
  Eigen::VectorXd y;
  Eigen::MatrixXd h, r;
};

// N lines, parallel or orthogonal walls at 0.5 m + 0.1 m i, with a dense P as
// after mapping them from a moving robot: P = 1e-4 I + G G' (G couples every
// entry through the pose). Built directly: N AddLine calls would copy P N times.
Problem MakeProblem(int n_lines) {
  Problem p;
  const long n = LineEkf::kFirstLine + 2L * n_lines;
  Eigen::VectorXd& x = p.ekf.mutable_x();
  x = Eigen::VectorXd::Zero(n);
  x.head<6>() << 0.3, -0.2, 0.1, 1, 1, 1;
  for (int i = 0; i < n_lines; ++i) {
    x(LineEkf::RhoIndex(i)) = 0.5 + 0.1 * i;
    x(LineEkf::ThetaIndex(i)) = (i % 4) * M_PI / 2 - M_PI / 2 + 0.01;
  }
  Eigen::MatrixXd g(n, 3);
  for (long i = 0; i < n; ++i) {
    for (long c = 0; c < 3; ++c) g(i, c) = 0.01 * std::cos(0.7 * static_cast<double>(i) + 1.3 * static_cast<double>(c));
  }
  p.ekf.SetCovariance(Eigen::MatrixXd::Identity(n, n) * 1e-4 + g * g.transpose());
  const Eigen::Matrix2d r = Eigen::Matrix2d::Identity() * 1e-4;
  p.h = Eigen::MatrixXd::Zero(3, n);
  const int k = n_lines / 2;
  Eigen::Matrix<double, 2, 5> j;
  PredictObservation(p.ekf.pose(), p.ekf.rho(k), p.ekf.theta(k), &j);
  p.h.leftCols<3>() = j.leftCols<3>();
  p.h.middleCols<2>(LineEkf::RhoIndex(k)) = j.rightCols<2>();
  p.h(2, LineEkf::ThetaIndex(k)) = 1;
  p.h(2, LineEkf::ThetaIndex(0)) = -1;
  p.r = Eigen::MatrixXd::Zero(3, 3);
  p.r.topLeftCorner<2, 2>() = r;
  p.r(2, 2) = 1e-6;
  p.y = Eigen::VectorXd::Zero(3);
  return p;
}

void BM_EkfUpdateReference(benchmark::State& state) {
  Problem p = MakeProblem(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    p.ekf.UpdateReference(p.y, p.h, p.r);
    benchmark::DoNotOptimize(p.ekf.x().data());
    benchmark::ClobberMemory();
  }
  state.counters["state_dim"] = static_cast<double>(p.ekf.x().size());
}

void BM_EkfUpdateInPlace(benchmark::State& state) {
  Problem p = MakeProblem(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    p.ekf.Update(p.y, p.h, p.r);
    benchmark::DoNotOptimize(p.ekf.x().data());
    benchmark::ClobberMemory();
  }
  state.counters["state_dim"] = static_cast<double>(p.ekf.x().size());
}

// Line deletion at a merge (rows and columns of one line out of P).
void BM_EkfRemoveLine(benchmark::State& state) {
  const int n_lines = static_cast<int>(state.range(0));
  Problem p = MakeProblem(n_lines + 1);
  const Eigen::Matrix2d r = Eigen::Matrix2d::Identity() * 1e-4;
  for (auto _ : state) {
    p.ekf.RemoveLine(n_lines / 2);
    state.PauseTiming();
    p.ekf.AddLine({1.0, 0.01}, r);
    state.ResumeTiming();
  }
  state.counters["state_dim"] = static_cast<double>(p.ekf.x().size());
}

// One prediction (every control period): the robot block and the pose's
// cross-covariances with every line (slam/odometry.h calibrated wheel motion).
void BM_EkfPredict(benchmark::State& state) {
  Problem p = MakeProblem(static_cast<int>(state.range(0)));
  const WheelMotion wheels{0.0100, 0.0102};
  for (auto _ : state) {
    p.ekf.Predict(wheels, 0.23, MotionNoise{}, 1e-7, 2e-4);
    benchmark::DoNotOptimize(p.ekf.x().data());
    benchmark::ClobberMemory();
  }
  state.counters["state_dim"] = static_cast<double>(p.ekf.x().size());
}

void Sizes(benchmark::internal::Benchmark* b) {
  for (const int lines : {50, 100, 200, 500, 1000}) b->Arg(lines);
  b->Unit(benchmark::kMicrosecond);
}
BENCHMARK(BM_EkfUpdateReference)->Apply(Sizes);
BENCHMARK(BM_EkfUpdateInPlace)->Apply(Sizes);
BENCHMARK(BM_EkfRemoveLine)->Apply(Sizes);
BENCHMARK(BM_EkfPredict)->Apply(Sizes);

}  // namespace
}  // namespace irslam::slam

BENCHMARK_MAIN();
