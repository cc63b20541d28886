// A minimal SVG line chart for the accuracy report.
#ifndef IRSLAM_TESTS_TOOLS_SVG_CHART_H_
#define IRSLAM_TESTS_TOOLS_SVG_CHART_H_

#include <string>
#include <utility>
#include <vector>

namespace irslam::report {

struct Series {
  std::string name;
  std::string color;
  std::vector<std::pair<double, double>> points;
  bool dashed = false;
};

std::string LineChart(const std::string& title, const std::string& xlabel, const std::string& ylabel,
                      const std::vector<Series>& series, bool log_y = false);

}  // namespace irslam::report

#endif  // IRSLAM_TESTS_TOOLS_SVG_CHART_H_
