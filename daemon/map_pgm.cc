#include "daemon/map_pgm.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "io/file_io.h"

namespace irslam {
namespace {

constexpr double kMarginM = 0.25;    // unknown border around what was mapped
constexpr double kMaxExtentM = 200;  // a larger map is refused (a corrupted file)

bool IsPoint(const nlohmann::json& p) {
  return p.is_array() && p.size() == 2 && p[0].is_number() && p[1].is_number() &&
         std::isfinite(p[0].get<double>()) && std::isfinite(p[1].get<double>());
}

bool IsBox(const nlohmann::json& b) {
  if (!b.is_array() || b.size() != 4) return false;
  for (const auto& v : b) {
    if (!v.is_number() || !std::isfinite(v.get<double>())) return false;
  }
  return b[0].get<double>() <= b[2].get<double>() && b[1].get<double>() <= b[3].get<double>();
}

class Grid {
 public:
  explicit Grid(PgmImage* img) : img_(img) {}
  // The cell holding map point (x, y), or false when outside.
  bool Cell(double x, double y, int* col, int* row) const {
    const double fc = (x - img_->origin_x) / img_->resolution_m;
    const double fr = (y - img_->origin_y) / img_->resolution_m;
    if (fc < 0 || fr < 0 || fc >= img_->width || fr >= img_->height) return false;
    *col = static_cast<int>(fc);
    *row = img_->height - 1 - static_cast<int>(fr);
    return true;
  }
  void Set(double x, double y, uint8_t v) {
    int c = 0, r = 0;
    if (Cell(x, y, &c, &r)) img_->cells[static_cast<size_t>(r) * img_->width + c] = v;
  }
  // Every cell whose centre lies inside [x0, x1] x [y0, y1].
  void FillBox(double x0, double y0, double x1, double y1, uint8_t v) {
    const double res = img_->resolution_m;
    for (int row = 0; row < img_->height; ++row) {
      const double y = img_->origin_y + (img_->height - 1 - row + 0.5) * res;
      if (y < y0 || y > y1) continue;
      for (int col = 0; col < img_->width; ++col) {
        const double x = img_->origin_x + (col + 0.5) * res;
        if (x >= x0 && x <= x1) img_->cells[static_cast<size_t>(row) * img_->width + col] = v;
      }
    }
  }
  // Every cell the segment passes through (sampled at a quarter cell).
  void Segment(double x0, double y0, double x1, double y1, uint8_t v) {
    const double len = std::hypot(x1 - x0, y1 - y0);
    const int n = std::max(1, static_cast<int>(std::ceil(len / (0.25 * img_->resolution_m))));
    for (int i = 0; i <= n; ++i) {
      const double s = static_cast<double>(i) / n;
      Set(x0 + s * (x1 - x0), y0 + s * (y1 - y0), v);
    }
  }

 private:
  PgmImage* img_;
};

}  // namespace

std::optional<PgmImage> RenderPgm(const nlohmann::json& map, double resolution_m, std::string* error) {
  if (!(resolution_m >= 0.001 && resolution_m <= 1.0)) {
    *error = "resolution must be within 0.001 and 1 m";
    return std::nullopt;
  }
  if (!map.is_object() || !map.contains("lines") || !map["lines"].is_array()) {
    *error = "the map has no \"lines\" array";
    return std::nullopt;
  }
  double xmin = 1e300, ymin = 1e300, xmax = -1e300, ymax = -1e300;
  const auto extend = [&](double x, double y) {
    xmin = std::min(xmin, x), xmax = std::max(xmax, x);
    ymin = std::min(ymin, y), ymax = std::max(ymax, y);
  };
  std::vector<std::array<double, 4>> segments;
  for (const auto& l : map["lines"]) {
    if (!l.is_object() || !IsPoint(l.value("p0", nlohmann::json())) || !IsPoint(l.value("p1", nlohmann::json()))) {
      *error = "a line without p0 and p1";
      return std::nullopt;
    }
    const auto& p0 = l["p0"];
    const auto& p1 = l["p1"];
    segments.push_back({p0[0].get<double>(), p0[1].get<double>(), p1[0].get<double>(), p1[1].get<double>()});
    extend(segments.back()[0], segments.back()[1]);
    extend(segments.back()[2], segments.back()[3]);
  }
  std::optional<std::array<double, 4>> room;
  if (map.contains("room") && map["room"].is_object() && IsBox(map["room"].value("box", nlohmann::json()))) {
    const auto& b = map["room"]["box"];
    room = std::array<double, 4>{b[0].get<double>(), b[1].get<double>(), b[2].get<double>(), b[3].get<double>()};
    extend((*room)[0], (*room)[1]);
    extend((*room)[2], (*room)[3]);
  }
  if (segments.empty() && !room) {
    *error = "the map has neither lines nor a room";
    return std::nullopt;
  }
  if (xmax - xmin > kMaxExtentM || ymax - ymin > kMaxExtentM) {
    *error = "the map is larger than 200 m a side";
    return std::nullopt;
  }
  PgmImage img;
  img.resolution_m = resolution_m;
  img.origin_x = std::floor((xmin - kMarginM) / resolution_m) * resolution_m;
  img.origin_y = std::floor((ymin - kMarginM) / resolution_m) * resolution_m;
  img.width = static_cast<int>(std::ceil((xmax + kMarginM - img.origin_x) / resolution_m));
  img.height = static_cast<int>(std::ceil((ymax + kMarginM - img.origin_y) / resolution_m));
  img.cells.assign(static_cast<size_t>(img.width) * img.height, kPgmUnknown);
  Grid grid(&img);
  if (room) grid.FillBox((*room)[0], (*room)[1], (*room)[2], (*room)[3], kPgmFree);
  if (map.contains("objects") && map["objects"].is_array()) {
    for (const auto& o : map["objects"]) {
      if (!o.is_object() || !IsBox(o.value("box", nlohmann::json()))) continue;
      const auto& b = o["box"];
      grid.FillBox(b[0].get<double>(), b[1].get<double>(), b[2].get<double>(), b[3].get<double>(), kPgmUnknown);
    }
  }
  for (const auto& s : segments) grid.Segment(s[0], s[1], s[2], s[3], kPgmOccupied);
  return img;
}

std::string EncodePgm(const PgmImage& image) {
  std::string out = "P5\n# irslam map (map frame), " + std::to_string(image.resolution_m) + " m/cell\n" +
                    std::to_string(image.width) + " " + std::to_string(image.height) + "\n255\n";
  out.append(image.cells.begin(), image.cells.end());
  return out;
}

std::string MapServerYaml(const PgmImage& image, const std::string& image_file) {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "image: %s\nresolution: %.6g\norigin: [%.6f, %.6f, 0.0]\nnegate: 0\noccupied_thresh: 0.65\n"
                "free_thresh: 0.196\n",
                image_file.c_str(), image.resolution_m, image.origin_x, image.origin_y);
  return buf;
}

std::string PgmYamlPath(const std::string& pgm_path) {
  const std::string ext = ".pgm";
  if (pgm_path.size() > ext.size() && pgm_path.compare(pgm_path.size() - ext.size(), ext.size(), ext) == 0) {
    return pgm_path.substr(0, pgm_path.size() - ext.size()) + ".yaml";
  }
  return pgm_path + ".yaml";
}

bool WritePgmMap(const nlohmann::json& map, const std::string& pgm_path, double resolution_m, std::string* error) {
  const auto image = RenderPgm(map, resolution_m, error);
  if (!image) return false;
  const auto slash = pgm_path.rfind('/');
  const std::string file = slash == std::string::npos ? pgm_path : pgm_path.substr(slash + 1);
  const std::pair<std::string, std::string> outputs[] = {{pgm_path, EncodePgm(*image)},
                                                         {PgmYamlPath(pgm_path), MapServerYaml(*image, file)}};
  for (const auto& [path, text] : outputs) {
    if (!WriteFileReplacing(path, text)) {
      *error = "cannot write " + path;
      return false;
    }
  }
  return true;
}

}  // namespace irslam
