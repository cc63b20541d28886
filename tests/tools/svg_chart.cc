#include "tests/tools/svg_chart.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace irslam::report {

std::string LineChart(const std::string& title, const std::string& xlabel, const std::string& ylabel,
                      const std::vector<Series>& series, bool log_y) {
  const double W = 900, H = 420, L = 70, R = 300, T = 40, B = 50;
  double x0 = 1e18, x1 = -1e18, y0 = 1e18, y1 = -1e18;
  const auto fy = [&](double y) { return log_y ? std::log10(std::max(y, 1e-12)) : y; };
  for (const auto& s : series) {
    for (const auto& [x, y] : s.points) {
      x0 = std::min(x0, x);
      x1 = std::max(x1, x);
      y0 = std::min(y0, fy(y));
      y1 = std::max(y1, fy(y));
    }
  }
  if (x0 > x1) x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  if (!log_y) y0 = std::min(0.0, y0);
  if (y1 <= y0) y1 = y0 + 1;
  if (x1 <= x0) x1 = x0 + 1;
  y1 += 0.05 * (y1 - y0);
  const auto px = [&](double x) { return L + (x - x0) / (x1 - x0) * (W - L - R); };
  const auto py = [&](double y) { return H - B - (fy(y) - y0) / (y1 - y0) * (H - T - B); };
  std::ostringstream o;
  o << "<svg xmlns='http://www.w3.org/2000/svg' width='" << W << "' height='" << H
    << "' font-family='sans-serif' font-size='12'>\n<rect width='100%' height='100%' fill='white'/>\n"
    << "<text x='" << W / 2 << "' y='22' text-anchor='middle' font-size='15'>" << title << "</text>\n"
    << "<line x1='" << L << "' y1='" << H - B << "' x2='" << W - R << "' y2='" << H - B << "' stroke='black'/>\n"
    << "<line x1='" << L << "' y1='" << T << "' x2='" << L << "' y2='" << H - B << "' stroke='black'/>\n";
  char buf[64];
  for (int i = 0; i <= 5; ++i) {
    const double xv = x0 + (x1 - x0) * i / 5;
    std::snprintf(buf, sizeof buf, "%.3g", xv);
    o << "<text x='" << px(xv) << "' y='" << H - B + 16 << "' text-anchor='middle'>" << buf << "</text>\n";
    const double yv = y0 + (y1 - y0) * i / 5;
    std::snprintf(buf, sizeof buf, "%.3g", log_y ? std::pow(10, yv) : yv);
    const double yy = H - B - (yv - y0) / (y1 - y0) * (H - T - B);
    o << "<text x='" << L - 6 << "' y='" << yy + 4 << "' text-anchor='end'>" << buf << "</text>\n"
      << "<line x1='" << L << "' y1='" << yy << "' x2='" << W - R << "' y2='" << yy
      << "' stroke='#ddd'/>\n";
  }
  o << "<text x='" << (L + W - R) / 2 << "' y='" << H - 12 << "' text-anchor='middle'>" << xlabel << "</text>\n"
    << "<text x='16' y='" << (T + H - B) / 2 << "' text-anchor='middle' transform='rotate(-90 16 "
    << (T + H - B) / 2 << ")'>" << ylabel << "</text>\n";
  int k = 0;
  for (const auto& s : series) {
    o << "<polyline fill='none' stroke='" << s.color << "' stroke-width='1.6'"
      << (s.dashed ? " stroke-dasharray='5,3'" : "") << " points='";
    for (const auto& [x, y] : s.points) o << px(x) << "," << py(y) << " ";
    o << "'/>\n<line x1='" << W - R + 10 << "' y1='" << T + 10 + 18 * k << "' x2='" << W - R + 34
      << "' y2='" << T + 10 + 18 * k << "' stroke='" << s.color << "' stroke-width='2'"
      << (s.dashed ? " stroke-dasharray='5,3'" : "") << "/>\n<text x='" << W - R + 40 << "' y='"
      << T + 14 + 18 * k << "'>" << s.name << "</text>\n";
    ++k;
  }
  o << "</svg>\n";
  return o.str();
}

}  // namespace irslam::report
