// fploc map render (SVG / PNG like the paper's Fig. 2) and export-pgm (ROS map_server PGM + YAML).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "fploc/annf/annf.h"
#include "fploc/core/text_out.h"
#include "fploc/floorplan/png.h"
#include "map_tool.h"

namespace fploc {
namespace {

std::string lower_ext(const std::string& p) {
  std::string e = std::filesystem::path(p).extension().string();
  for (auto& c : e) c = char(std::tolower((unsigned char)c));
  return e;
}

// A stable pastel colour per element id.
void colour(uint32_t id, uint8_t rgb[3]) {
  uint32_t h = id * 2654435761u;
  const double hue = (h % 360) / 60.0, s = 0.45, v = 0.95;
  const double c = v * s, x = c * (1 - std::abs(std::fmod(hue, 2.0) - 1)), m = v - c;
  double r = 0, g = 0, b = 0;
  switch (int(hue)) {
    case 0: r = c, g = x; break;
    case 1: r = x, g = c; break;
    case 2: g = c, b = x; break;
    case 3: g = x, b = c; break;
    case 4: r = x, b = c; break;
    default: r = c, b = x; break;
  }
  rgb[0] = uint8_t((r + m) * 255);
  rgb[1] = uint8_t((g + m) * 255);
  rgb[2] = uint8_t((b + m) * 255);
}

void write_svg(const annf::Annf& f, const std::string& out, int width) {
  const FloorPlan& plan = f.plan();
  const Box2 b = plan.bounds();
  const double pad = 0.02 * b.size().maxCoeff() + 0.1;
  const double W = b.size().x() + 2 * pad, H = b.size().y() + 2 * pad;
  std::ofstream s(out);
  if (!s) throw std::runtime_error(out + ": cannot write");
  const double sw = b.size().maxCoeff() / 1500.0;
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << int(width * H / W)
    << "\" viewBox=\"" << b.min.x() - pad << " " << -(b.max.y() + pad) << " " << W << " " << H << "\">\n"
    << "<g transform=\"scale(1,-1)\">\n<g stroke=\"#00000030\" stroke-width=\"" << sw * 0.5 << "\">\n";
  f.for_each_leaf([&](const Box2& box, int, const uint32_t* ids, int n) {
    if (box.max.x() < b.min.x() - pad || box.min.x() > b.max.x() + pad || box.max.y() < b.min.y() - pad ||
        box.min.y() > b.max.y() + pad)
      return;
    uint8_t c[3] = {235, 235, 235};
    if (n > 0) colour(ids[0], c);
    char buf[64];
    std::snprintf(buf, sizeof buf, "#%02x%02x%02x", c[0], c[1], c[2]);
    s << "<rect x=\"" << box.min.x() << "\" y=\"" << box.min.y() << "\" width=\"" << box.size().x() << "\" height=\""
      << box.size().y() << "\" fill=\"" << buf << "\"/>\n";
  });
  s << "</g>\n<g fill=\"none\" stroke=\"#000\" stroke-width=\"" << sw * 2 << "\">\n";
  for (const auto& e : plan.elements) {
    if (e.kind == ElementKind::kSegment) {
      s << "<line x1=\"" << e.a.x() << "\" y1=\"" << e.a.y() << "\" x2=\"" << e.b.x() << "\" y2=\"" << e.b.y() << "\"/>\n";
    } else if (e.kind == ElementKind::kCircle) {
      s << "<circle cx=\"" << e.c.x() << "\" cy=\"" << e.c.y() << "\" r=\"" << e.r << "\"/>\n";
    } else {
      const Eigen::Vector2d p0 = e.c + e.r * Eigen::Vector2d(std::cos(e.a0), std::sin(e.a0));
      const Eigen::Vector2d p1 = e.c + e.r * Eigen::Vector2d(std::cos(e.a1), std::sin(e.a1));
      const int large = (e.a1 - e.a0) > M_PI ? 1 : 0;
      s << "<path d=\"M " << p0.x() << " " << p0.y() << " A " << e.r << " " << e.r << " 0 " << large << " 1 " << p1.x()
        << " " << p1.y() << "\"/>\n";
    }
  }
  s << "</g>\n</g>\n</svg>\n";
  if (!s) throw std::runtime_error(out + ": write error");
}

void write_png(const annf::Annf& f, const std::string& out, int width) {
  const FloorPlan& plan = f.plan();
  const Box2 b = plan.bounds();
  const double pad = 0.02 * b.size().maxCoeff() + 0.1;
  const double W = b.size().x() + 2 * pad, H = b.size().y() + 2 * pad;
  const int w = std::max(16, width), h = std::max(16, int(std::ceil(w * H / W)));
  const double px = W / w;
  annf::AnnfOptions xo;
  xo.mode = annf::AnnfMode::kExact;
  xo.max_depth = 9;
  const annf::Annf exact = annf::Annf::build(plan, xo);
  std::vector<uint8_t> img(size_t(w) * h * 3);
  std::vector<int64_t> leaf_key(size_t(w) * h, -1);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const Eigen::Vector2d p(b.min.x() - pad + (i + 0.5) * px, b.max.y() + pad - (j + 0.5) * px);
      uint8_t* c = &img[(size_t(j) * w + i) * 3];
      int n;
      const uint32_t* ids = f.lookup(p, &n);
      if (ids && n > 0) {
        colour(ids[0], c);
        Box2 lb;
        if (f.leaf_box(p, &lb)) leaf_key[size_t(j) * w + i] = int64_t(std::llround(lb.min.x() * 1e4)) * 1000003 + std::llround(lb.min.y() * 1e4);
      } else {
        c[0] = c[1] = c[2] = 235;
      }
      double d;
      exact.nearest(p, &d);
      if (d <= 0.75 * px) c[0] = c[1] = c[2] = 0;
    }
  for (int j = 1; j < h; ++j)
    for (int i = 1; i < w; ++i) {
      const size_t k = size_t(j) * w + i;
      if (leaf_key[k] != leaf_key[k - 1] || leaf_key[k] != leaf_key[k - w])
        for (int q = 0; q < 3; ++q) img[k * 3 + q] = uint8_t(img[k * 3 + q] * 0.8);
    }
  write_rgb_png(out, w, h, img);
}

}  // namespace


int cmd_render(const FloorPlan& plan, const RenderArgs& a) {
  annf::Annf f;
  if (!a.map.empty()) {
    f = annf::Annf::load(a.map);
  } else {
    annf::AnnfOptions o;
    o.max_depth = a.depth;
    f = annf::Annf::build(plan, o);
  }
  const std::string ext = lower_ext(a.out);
  if (ext == ".svg")
    write_svg(f, a.out, a.width);
  else if (ext == ".png")
    write_png(f, a.out, a.width);
  else
    throw std::runtime_error(a.out + ": output must be .svg or .png");
  std::cerr << "fploc map render: " << f.stats().leaves << " leaf fields, " << f.plan().elements.size()
            << " elements -> " << a.out << "\n";
  return 0;
}

int cmd_export_pgm(const FloorPlan& plan, const PgmArgs& a, bool as_json) {
  if (!(a.resolution > 0)) throw std::runtime_error("--resolution must be > 0");
  const Box2 b = plan.bounds();
  const double ox = b.min.x() - a.margin, oy = b.min.y() - a.margin;
  const double w_m = b.size().x() + 2 * a.margin, h_m = b.size().y() + 2 * a.margin;
  const double wd = std::ceil(w_m / a.resolution), hd = std::ceil(h_m / a.resolution);
  if (wd * hd > 4e8) throw std::runtime_error("map too large at this resolution");
  const int w = int(wd), h = int(hd);
  annf::AnnfOptions xo;
  xo.mode = annf::AnnfMode::kExact;
  xo.max_depth = 9;
  const annf::Annf exact = annf::Annf::build(plan, xo);
  // A pixel is occupied when an element passes through it (centre distance <= half diagonal) or is
  // within half the requested wall thickness.
  const double occ = std::max(a.resolution * std::sqrt(0.5), a.thickness / 2);
  std::vector<uint8_t> img(size_t(w) * h, 254);
  size_t occupied = 0;
  for (int row = 0; row < h; ++row) {
    const int j = h - 1 - row;  // top row first
    for (int i = 0; i < w; ++i) {
      double d;
      exact.nearest(Eigen::Vector2d(ox + (i + 0.5) * a.resolution, oy + (j + 0.5) * a.resolution), &d);
      if (d <= occ) {
        img[size_t(row) * w + i] = 0;
        ++occupied;
      }
    }
  }
  std::filesystem::create_directories(a.out);
  const std::string pgm = (std::filesystem::path(a.out) / (a.name + ".pgm")).string();
  const std::string yaml = (std::filesystem::path(a.out) / (a.name + ".yaml")).string();
  {
    std::ofstream f(pgm, std::ios::binary);
    if (!f) throw std::runtime_error(pgm + ": cannot write");
    f << "P5\n# fploc map export-pgm " << plan.source << "\n" << w << " " << h << "\n255\n";
    f.write(reinterpret_cast<const char*>(img.data()), std::streamsize(img.size()));
    if (!f) throw std::runtime_error(pgm + ": write error");
  }
  {
    std::ofstream f(yaml);
    if (!f) throw std::runtime_error(yaml + ": cannot write");
    f.precision(10);
    f << "image: " << a.name << ".pgm\nresolution: " << a.resolution << "\norigin: [" << ox << ", " << oy
      << ", 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.25\nmode: trinary\n";
  }
  std::cerr << "fploc map export-pgm: " << w << " x " << h << " pixels at " << a.resolution << " m, " << occupied
            << " occupied -> " << pgm << ", " << yaml << "\n";
  if (as_json)
    std::cout << fploc::json_text(nlohmann::json({{"pgm", pgm}, {"yaml", yaml}, {"width", w}, {"height", h},
                                                  {"resolution_m", a.resolution}, {"origin", {ox, oy, 0.0}}, {"occupied", occupied}}),
                                  1)
              << "\n";
  return 0;
}

}  // namespace fploc
