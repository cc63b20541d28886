#include "daemon/map_svg.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

namespace irslam {
namespace {

struct Xf {  // map frame -> drawing frame (world frame when truth is known)
  double x = 0, y = 0, th = 0;
  void Apply(double mx, double my, double* ox, double* oy) const {
    *ox = x + std::cos(th) * mx - std::sin(th) * my;
    *oy = y + std::sin(th) * mx + std::cos(th) * my;
  }
};

class Canvas {
 public:
  void Extend(double x, double y) {
    xmin_ = std::min(xmin_, x);
    xmax_ = std::max(xmax_, x);
    ymin_ = std::min(ymin_, y);
    ymax_ = std::max(ymax_, y);
  }
  void Line(double x0, double y0, double x1, double y1, const char* color, double width,
            const char* extra = "") {
    Extend(x0, y0);
    Extend(x1, y1);
    body_ << "<line x1='" << x0 << "' y1='" << -y0 << "' x2='" << x1 << "' y2='" << -y1
          << "' stroke='" << color << "' stroke-width='" << width << "' " << extra << "/>\n";
  }
  void Poly(const std::vector<std::pair<double, double>>& pts, const char* color, double width,
            const char* fill = "none", bool closed = false) {
    if (pts.empty()) return;
    body_ << "<" << (closed ? "polygon" : "polyline") << " fill='" << fill << "' stroke='" << color
          << "' stroke-width='" << width << "' points='";
    for (const auto& [x, y] : pts) {
      Extend(x, y);
      body_ << x << "," << -y << " ";
    }
    body_ << "'/>\n";
  }
  void Raw(const std::string& s) { body_ << s; }
  std::string Finish(const std::string& legend) {
    if (xmin_ > xmax_) xmin_ = ymin_ = 0, xmax_ = ymax_ = 1;
    const double m = 0.3;
    std::ostringstream os;
    const double w = xmax_ - xmin_ + 2 * m, h = ymax_ - ymin_ + 2 * m;
    os << "<svg xmlns='http://www.w3.org/2000/svg' width='" << std::round(w * 150) << "' height='"
       << std::round(h * 150 + 40) << "' viewBox='" << xmin_ - m << " " << -ymax_ - m << " " << w
       << " " << h + 0.27 << "'>\n"
       << "<rect x='" << xmin_ - m << "' y='" << -ymax_ - m << "' width='" << w << "' height='"
       << h + 0.27 << "' fill='white'/>\n"
       << body_.str() << "<text x='" << xmin_ - m + 0.05 << "' y='" << -ymin_ + m + 0.15
       << "' font-size='0.11' font-family='sans-serif'>" << legend << "</text>\n</svg>\n";
    return os.str();
  }

 private:
  double xmin_ = 1e9, xmax_ = -1e9, ymin_ = 1e9, ymax_ = -1e9;
  std::ostringstream body_;
};

// Map -> world: the robot's first pose is known in both frames (the truth's
// start and the map trajectory's first point), so world = start o map0^-1.
Xf MapToWorld(const nlohmann::json& map, const nlohmann::json& truth) {
  const auto& p = truth["trajectory"][0];
  double mx = 0, my = 0, mth = 0;
  if (map.is_object() && map.contains("trajectory") && !map["trajectory"].empty()) {
    const auto& q = map["trajectory"][0];
    mx = q[1].get<double>();
    my = q[2].get<double>();
    mth = q[3].get<double>();
  }
  const double th = p[3].get<double>() - mth;
  const double ct = std::cos(th), st = std::sin(th);
  return {p[1].get<double>() - (ct * mx - st * my), p[2].get<double>() - (st * mx + ct * my), th};
}

// The true room: its outline and its furniture.
void DrawWorld(Canvas& c, const nlohmann::json& world) {
  std::vector<std::pair<double, double>> outline;
  if (world.contains("outline")) {
    for (const auto& p : world["outline"]) outline.emplace_back(p[0], p[1]);
  } else if (world.contains("room")) {
    const double w = world["room"][0], h = world["room"][1];
    outline = {{0, 0}, {w, 0}, {w, h}, {0, h}};
  }
  c.Poly(outline, "#999", 0.03, "#f4f4f4", true);
  for (const auto& b : world.value("objects", nlohmann::json::array())) {
    const double x0 = b[0], y0 = b[1], x1 = b[2], y1 = b[3];
    c.Poly({{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}, "#999", 0.02, "#ddd", true);
  }
}

void DrawTrajectory(Canvas& c, const Xf& xf, const nlohmann::json& t, const char* color, double width,
                    bool map_frame) {
  std::vector<std::pair<double, double>> pts;
  for (const auto& p : t) {
    double x = p[1], y = p[2];
    if (map_frame) xf.Apply(p[1].get<double>(), p[2].get<double>(), &x, &y);
    pts.emplace_back(x, y);
  }
  c.Poly(pts, color, width);
}

// Cleaning (contracts §7): the floor swept (the estimated path during cleaning,
// as wide as the cleaning width), each cell's outline and its route.
void DrawCleaning(Canvas& c, const Xf& xf, const nlohmann::json& map) {
  const auto& cl = map["cleaning"];
  const double t0 = cl.value("started_t", 0.0);
  const double t1 = cl["finished_t"].is_number() ? cl["finished_t"].get<double>() : 1e18;
  std::vector<std::pair<double, double>> swept;
  for (const auto& p : map.value("trajectory", nlohmann::json::array())) {
    if (p[0].get<double>() < t0 || p[0].get<double>() > t1) continue;
    double x, y;
    xf.Apply(p[1].get<double>(), p[2].get<double>(), &x, &y);
    swept.emplace_back(x, y);
  }
  std::ostringstream w;
  w << cl.value("width_m", 0.34);
  const std::string width = w.str();
  std::ostringstream sw;
  sw << "<polyline fill='none' stroke='rgba(60,190,110,0.25)' stroke-width='" << width
     << "' stroke-linecap='round' stroke-linejoin='round' points='";
  for (const auto& [x, y] : swept) sw << x << "," << -y << " ";
  sw << "'/>\n";
  c.Raw(sw.str());
  const auto to_pts = [&](const nlohmann::json& a) {
    std::vector<std::pair<double, double>> pts;
    for (const auto& q : a) {
      double x, y;
      xf.Apply(q[0].get<double>(), q[1].get<double>(), &x, &y);
      pts.emplace_back(x, y);
    }
    return pts;
  };
  for (const auto& cell : cl.value("cells", nlohmann::json::array())) {
    const bool done = cell.value("done", false);
    c.Poly(to_pts(cell.value("polygon", nlohmann::json::array())),
           done ? "#2a6" : (cell.value("unreachable", false) ? "#c33" : "#aaa"), 0.01, "none", true);
    c.Poly(to_pts(cell.value("route", nlohmann::json::array())), "#888", 0.006);
  }
}

// The mapped lines, each with its uncertainty and id.
void DrawLines(Canvas& c, const Xf& xf, const nlohmann::json& map) {
  for (const auto& l : map.value("lines", nlohmann::json::array())) {
    double x0, y0, x1, y1;
    xf.Apply(l["p0"][0].get<double>(), l["p0"][1].get<double>(), &x0, &y0);
    xf.Apply(l["p1"][0].get<double>(), l["p1"][1].get<double>(), &x1, &y1);
    c.Line(x0, y0, x1, y1, "#000", 0.03, "stroke-linecap='round'");
    // Uncertainty of the line: an ellipse at its centre, sigma of rho across the
    // line and sigma of theta times half-length along it (x3 for visibility).
    const double srr = std::sqrt(std::max(0.0, l["cov"][0][0].get<double>()));
    const double stt = std::sqrt(std::max(0.0, l["cov"][1][1].get<double>()));
    const double len = l.value("length", 0.0);
    const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
    const double ang = std::atan2(y1 - y0, x1 - x0) * 180 / M_PI;
    std::ostringstream e;
    e << "<ellipse cx='" << cx << "' cy='" << -cy << "' rx='" << std::max(0.01, 3 * stt * len / 2)
      << "' ry='" << std::max(0.005, 3 * srr) << "' transform='rotate(" << -ang << " " << cx
      << " " << -cy << ")' fill='none' stroke='#c0c' stroke-width='0.008'/>\n";
    c.Raw(e.str());
    std::ostringstream t;
    t << "<text x='" << cx << "' y='" << -cy << "' font-size='0.09' fill='#000'>" << l["id"]
      << "</text>\n";
    c.Raw(t.str());
  }
}

// The modelled objects' boxes (wall contacts orange, furniture blue; filled when complete).
void DrawObjects(Canvas& c, const Xf& xf, const nlohmann::json& map) {
  for (const auto& o : map.value("objects", nlohmann::json::array())) {
    if (!o.contains("box") || !o["box"].is_array()) continue;
    const auto& b = o["box"];
    std::vector<std::pair<double, double>> pts;
    const double bx[4][2] = {{b[0], b[1]}, {b[2], b[1]}, {b[2], b[3]}, {b[0], b[3]}};
    for (const auto& q : bx) {
      double x, y;
      xf.Apply(q[0], q[1], &x, &y);
      pts.emplace_back(x, y);
    }
    const bool complete = o.value("complete", false);
    const bool wall = o.value("kind", "") == "wall_contact";
    c.Poly(pts, wall ? "#e80" : "#08a", 0.02,
           complete ? (wall ? "rgba(238,136,0,0.2)" : "rgba(0,136,170,0.2)") : "none", true);
  }
}

}  // namespace

std::string RenderMapSvg(const nlohmann::json& map, const nlohmann::json& truth,
                         const nlohmann::json& world) {
  Canvas c;
  Xf xf;
  const bool have_truth = truth.is_object() && truth.contains("trajectory") &&
                          !truth["trajectory"].empty();
  if (have_truth) xf = MapToWorld(map, truth);
  if (world.is_object()) DrawWorld(c, world);
  const bool cleaning = map.is_object() && map.contains("cleaning") && map["cleaning"].is_object();
  if (cleaning) DrawCleaning(c, xf, map);
  if (have_truth) {
    DrawTrajectory(c, xf, truth.value("odometry", nlohmann::json::array()), "#2a2", 0.012, false);
    DrawTrajectory(c, xf, truth["trajectory"], "#d22", 0.012, false);
  }
  if (map.is_object()) {
    DrawTrajectory(c, xf, map.value("trajectory", nlohmann::json::array()), "#36c", 0.015, true);
    DrawLines(c, xf, map);
    DrawObjects(c, xf, map);
  }
  std::string legend = "black: mapped lines (magenta: 3-sigma), blue: SLAM trajectory";
  if (have_truth) legend += ", red: true trajectory, green: odometry";
  if (cleaning) legend += ", cleaning: cells (green done, red unreachable), routes (grey), swept floor (light green)";
  if (map.is_object()) legend += " | state: " + map.value("state", std::string("?"));
  return c.Finish(legend);
}

}  // namespace irslam
