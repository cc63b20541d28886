// irslam-weights: the paper's Appendix 1 procedure for the weights of eq. (8).
//   irslam-weights LINES.jsonl [--min-length L]
// Reads recorded line observations (`irslam-sim run --lines-out`, one JSON object
// per line with length, c_rho_rho, c_theta_theta), keeps lines longer than 70 % of
// the minimum length L, and for each uncertainty c (c_rho_rho, c_theta_theta, and
// 1/l for the length term) builds the accumulated histogram: c_d is where it
// reaches 50 % of the lines, c_min = c_d - min(c), c_max = max(c) - c_d, and
// eqs. (17)-(18): w = 1 / max(c_min, c_max). Prints the three weights and the
// config keys to put them in.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <vector>

#include "io/json_text.h"

namespace {

double Weight(std::vector<double> c) {
  std::sort(c.begin(), c.end());
  const double cd = c[c.size() / 2];  // 50 % of the accumulated histogram
  const double spread = std::max(cd - c.front(), c.back() - cd);
  return spread > 0 ? 1.0 / spread : 0.0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"irslam-weights: eq. (8) weights from recorded line observations (Appendix 1)"};
  std::string path;
  double min_length = 0.30;
  app.add_option("lines", path, "Recorded observations (irslam-sim run --lines-out)")->required();
  app.add_option("--min-length", min_length, "L, the extraction's minimum line length (m)");
  CLI11_PARSE(app, argc, argv);
  std::ifstream in(path);
  if (!in) {
    std::fprintf(stderr, "irslam-weights: cannot read %s\n", path.c_str());
    return 2;
  }
  std::vector<double> crr, ctt, inv_l;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty()) continue;
    std::string error;
    auto j = irslam::ParseJsonText(line, &error);
    if (!j || !j->is_object() || !(*j)["length"].is_number() || !(*j)["c_rho_rho"].is_number() ||
        !(*j)["c_theta_theta"].is_number()) {
      std::fprintf(stderr, "irslam-weights: %s:%d: not a line observation\n", path.c_str(), n);
      return 2;
    }
    const double l = (*j)["length"];
    if (l < 0.7 * min_length) continue;
    crr.push_back((*j)["c_rho_rho"]);
    ctt.push_back((*j)["c_theta_theta"]);
    inv_l.push_back(1.0 / l);
  }
  if (crr.size() < 10) {
    std::fprintf(stderr, "irslam-weights: only %zu usable lines in %s (need 10 or more)\n", crr.size(),
                 path.c_str());
    return 1;
  }
  const double wl = Weight(inv_l), wr = Weight(crr), wt = Weight(ctt);
  std::printf("lines used: %zu\nwl = %.6g\nwrho = %.6g\nwtheta = %.6g\n", crr.size(), wl, wr, wt);
  std::printf("config: \"slam\": {\"extraction\": {\"weight_length\": %.6g, \"weight_rho\": %.6g, "
              "\"weight_theta\": %.6g}}\n", wl, wr, wt);
  return 0;
}
