#include "fploc/floorplan/occupancy.h"

#include "fploc/floorplan/io.h"

#include <png.h>
#include <yaml.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace fploc {
namespace {

[[noreturn]] void fail(const std::string& m) { throw std::runtime_error(m); }

std::string slurp(const std::string& path) { return read_input_file(path); }

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

// A YAML value: a scalar or a sequence of scalars, with the line it starts on.
struct YamlValue {
  std::vector<std::string> items;
  bool sequence = false;
  size_t line = 0;
};

// The top-level mapping of a map_server YAML (scalar keys; scalar or flat-sequence values), by libyaml.
std::map<std::string, YamlValue> parse_flat_mapping(const std::string& text, const std::string& source) {
  yaml_parser_t parser;
  if (!yaml_parser_initialize(&parser)) fail(source + ": cannot initialise the YAML parser");
  yaml_parser_set_input_string(&parser, reinterpret_cast<const unsigned char*>(text.data()), text.size());
  std::map<std::string, YamlValue> out;
  std::string key, err;
  bool have_key = false, in_seq = false, in_map = false, done = false;
  int depth = 0;
  YamlValue cur;
  while (!done && err.empty()) {
    yaml_event_t ev;
    if (!yaml_parser_parse(&parser, &ev)) {
      err = "line " + std::to_string(parser.problem_mark.line + 1) + ": YAML syntax error: " +
            (parser.problem ? parser.problem : "unknown");
      break;
    }
    const size_t line = ev.start_mark.line + 1;
    switch (ev.type) {
      case YAML_STREAM_END_EVENT: done = true; break;
      case YAML_MAPPING_START_EVENT:
        if (in_map) err = "line " + std::to_string(line) + ": " + (have_key ? key + ": " : "") + "nested mappings are not part of the map format";
        in_map = true;
        ++depth;
        break;
      case YAML_MAPPING_END_EVENT: in_map = false; break;
      case YAML_SEQUENCE_START_EVENT:
        if (!in_map || !have_key || in_seq) {
          err = "line " + std::to_string(line) + ": unexpected sequence";
          break;
        }
        in_seq = true;
        cur = {};
        cur.sequence = true;
        cur.line = line;
        break;
      case YAML_SEQUENCE_END_EVENT:
        in_seq = false;
        out[key] = cur;
        have_key = false;
        break;
      case YAML_SCALAR_EVENT: {
        const std::string v(reinterpret_cast<const char*>(ev.data.scalar.value), ev.data.scalar.length);
        if (!in_map) {
          err = "line " + std::to_string(line) + ": expected a mapping of keys (image, resolution, origin, ...)";
        } else if (in_seq) {
          cur.items.push_back(v);
        } else if (!have_key) {
          key = v;
          have_key = true;
          if (out.count(key)) err = "line " + std::to_string(line) + ": " + key + ": duplicate key";
        } else {
          YamlValue s;
          s.items = {v};
          s.line = line;
          out[key] = s;
          have_key = false;
        }
        break;
      }
      case YAML_ALIAS_EVENT: err = "line " + std::to_string(line) + ": aliases are not supported"; break;
      default: break;
    }
    yaml_event_delete(&ev);
  }
  yaml_parser_delete(&parser);
  if (!err.empty()) fail(source + ": " + err);
  return out;
}

double number(const std::map<std::string, YamlValue>& m, const std::string& source, const std::string& key,
              const std::string& s, size_t line) {
  double v = 0;
  const char* b = s.data();
  const char* e = s.data() + s.size();
  while (b < e && std::isspace((unsigned char)*b)) ++b;
  if (b < e && *b == '+') ++b;
  auto r = std::from_chars(b, e, v);
  if (r.ec != std::errc() || r.ptr != e || !std::isfinite(v))
    fail(source + ": " + key + " (line " + std::to_string(line) + "): expected a number, got '" + s + "'");
  (void)m;
  return v;
}

// Edit distance (a misspelt key's nearest known one).
size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diag = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

}  // namespace

Eigen::Vector2d OccupancyGrid::cell_centre(int i, int j) const {
  const double lx = (i + 0.5) * resolution, ly = (j + 0.5) * resolution;
  const double c = std::cos(origin_yaw), s = std::sin(origin_yaw);
  return {origin_x + c * lx - s * ly, origin_y + s * lx + c * ly};
}

MapYaml parse_map_yaml(const std::string& text, const std::string& source) {
  const auto m = parse_flat_mapping(text, source);
  MapYaml y;
  // map_server's keys; anything else is ignored as ROS does, with a warning (a misspelt key is a silent default).
  static const char* kKnown[] = {"image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh", "mode"};
  for (const auto& [k, v] : m) {
    if (std::find(std::begin(kKnown), std::end(kKnown), k) != std::end(kKnown)) continue;
    std::string near;
    size_t best = 3;  // at most 2 edits away
    for (const char* known : kKnown)
      if (const size_t d = edit_distance(lower(k), known); d < best) best = d, near = known;
    y.warnings.push_back(source + ": line " + std::to_string(v.line) + ": unknown key '" + k + "' (ignored, as map_server does" +
                         (near.empty() ? std::string("") : "; did you mean '" + near + "'?") + ")");
  }
  auto scalar = [&](const std::string& k, bool required) -> const YamlValue* {
    auto it = m.find(k);
    if (it == m.end()) {
      if (required) fail(source + ": " + k + ": missing (a map_server YAML needs image, resolution and origin)");
      return nullptr;
    }
    if (it->second.sequence) fail(source + ": " + k + " (line " + std::to_string(it->second.line) + "): expected a single value, got a list");
    return &it->second;
  };
  const YamlValue* v = scalar("image", true);
  y.image = v->items[0];
  if (y.image.empty()) fail(source + ": image: empty");
  v = scalar("resolution", true);
  y.resolution = number(m, source, "resolution", v->items[0], v->line);
  if (!(y.resolution > 0)) fail(source + ": resolution: must be > 0, got " + v->items[0]);
  auto o = m.find("origin");
  if (o == m.end()) fail(source + ": origin: missing (a map_server YAML needs image, resolution and origin)");
  if (!o->second.sequence || o->second.items.size() != 3)
    fail(source + ": origin (line " + std::to_string(o->second.line) + "): expected [x, y, yaw]");
  y.origin_x = number(m, source, "origin", o->second.items[0], o->second.line);
  y.origin_y = number(m, source, "origin", o->second.items[1], o->second.line);
  y.origin_yaw = number(m, source, "origin", o->second.items[2], o->second.line);
  if ((v = scalar("negate", false))) {
    const std::string s = lower(v->items[0]);
    if (s == "0" || s == "false") y.negate = false;
    else if (s == "1" || s == "true") y.negate = true;
    else fail(source + ": negate (line " + std::to_string(v->line) + "): expected 0 or 1, got '" + v->items[0] + "'");
  }
  if ((v = scalar("occupied_thresh", false))) y.occupied_thresh = number(m, source, "occupied_thresh", v->items[0], v->line);
  if ((v = scalar("free_thresh", false))) y.free_thresh = number(m, source, "free_thresh", v->items[0], v->line);
  if (!(y.occupied_thresh > 0 && y.occupied_thresh <= 1))
    fail(source + ": occupied_thresh: must be in (0, 1], got " + std::to_string(y.occupied_thresh));
  if (!(y.free_thresh >= 0 && y.free_thresh < y.occupied_thresh))
    fail(source + ": free_thresh: must be in [0, occupied_thresh), got " + std::to_string(y.free_thresh));
  if ((v = scalar("mode", false))) {
    const std::string s = lower(v->items[0]);
    if (s == "trinary") y.mode = OccupancyMode::kTrinary;
    else if (s == "scale") y.mode = OccupancyMode::kScale;
    else if (s == "raw") y.mode = OccupancyMode::kRaw;
    else fail(source + ": mode (line " + std::to_string(v->line) + "): expected trinary, scale or raw, got '" + v->items[0] + "'");
  }
  return y;
}

MapYaml read_map_yaml(const std::string& path) {
  MapYaml y = parse_map_yaml(slurp(path), path);
  for (const auto& w : y.warnings) std::cerr << "warning: " << w << "\n";
  std::filesystem::path img(y.image);
  if (img.is_relative()) img = std::filesystem::path(path).parent_path() / img;
  y.image_path = img.string();
  return y;
}

GrayImage read_pgm(const std::string& bytes, const std::string& source) {
  size_t pos = 0;
  // Header tokens separated by whitespace; '#' starts a comment to the end of the line.
  auto token = [&](const char* what) -> std::string {
    for (;;) {
      while (pos < bytes.size() && std::isspace((unsigned char)bytes[pos])) ++pos;
      if (pos < bytes.size() && bytes[pos] == '#') {
        while (pos < bytes.size() && bytes[pos] != '\n') ++pos;
        continue;
      }
      break;
    }
    const size_t b = pos;
    while (pos < bytes.size() && !std::isspace((unsigned char)bytes[pos]) && bytes[pos] != '#') ++pos;
    if (b == pos) fail(source + ": byte " + std::to_string(b) + ": " + what + ": missing (truncated PGM header)");
    return bytes.substr(b, pos - b);
  };
  auto integer = [&](const char* what, long lo, long hi) {
    const size_t at = pos;
    const std::string t = token(what);
    long v = 0;
    auto r = std::from_chars(t.data(), t.data() + t.size(), v);
    if (r.ec != std::errc() || r.ptr != t.data() + t.size() || v < lo || v > hi)
      fail(source + ": byte " + std::to_string(at) + ": " + what + ": expected an integer in [" + std::to_string(lo) + ", " +
           std::to_string(hi) + "], got '" + t + "'");
    return v;
  };
  const std::string magic = bytes.size() >= 2 ? bytes.substr(0, 2) : bytes;
  if (magic != "P5" && magic != "P2")
    fail(source + ": byte 0: magic: not a PGM (expected P5 or P2, got '" + magic.substr(0, 2) + "')");
  pos = 2;
  GrayImage img;
  img.width = int(integer("width", 1, 1 << 16));
  img.height = int(integer("height", 1, 1 << 16));
  const long maxval = integer("maxval", 1, 65535);
  const size_t n = size_t(img.width) * img.height;
  img.value.resize(n);
  auto scale = [&](long v) { return uint8_t(std::lround(double(v) * 255.0 / double(maxval))); };
  if (magic == "P5") {
    ++pos;  // the single whitespace after maxval
    const size_t bpp = maxval > 255 ? 2 : 1;
    if (bytes.size() < pos || bytes.size() - pos < n * bpp)
      fail(source + ": byte " + std::to_string(pos) + ": pixels: truncated pixel data (expected " + std::to_string(n * bpp) +
           " bytes, got " + std::to_string(bytes.size() >= pos ? bytes.size() - pos : 0) + ")");
    for (size_t k = 0; k < n; ++k) {
      long v = bpp == 1 ? (unsigned char)bytes[pos + k]
                        : long((unsigned char)bytes[pos + 2 * k]) << 8 | (unsigned char)bytes[pos + 2 * k + 1];
      if (v > maxval) fail(source + ": byte " + std::to_string(pos + k * bpp) + ": pixel value " + std::to_string(v) + " > maxval");
      img.value[k] = scale(v);
    }
    pos += n * bpp;
  } else {
    for (size_t k = 0; k < n; ++k) {
      size_t p = pos;
      while (p < bytes.size() && (std::isspace((unsigned char)bytes[p]) || bytes[p] == '#')) {
        if (bytes[p] == '#')
          while (p < bytes.size() && bytes[p] != '\n') ++p;
        else
          ++p;
      }
      if (p >= bytes.size())
        fail(source + ": byte " + std::to_string(p) + ": pixel data truncated: got " + std::to_string(k) + " of " +
             std::to_string(img.width) + "x" + std::to_string(img.height) + " = " + std::to_string(n) + " values");
      img.value[k] = scale(integer("pixel", 0, maxval));
    }
  }
  // More data than the header's width x height: a wrong header (the map would be silently cut). Trailing
  // whitespace is fine.
  size_t extra = pos;
  while (extra < bytes.size() && std::isspace((unsigned char)bytes[extra])) ++extra;
  if (extra < bytes.size())
    fail(source + ": byte " + std::to_string(pos) + ": the pixel data is longer than the header's " + std::to_string(img.width) +
         "x" + std::to_string(img.height) + " says: " + std::to_string(bytes.size() - pos) + " bytes after the image" +
         (magic == "P5" ? " (" + std::to_string((bytes.size() - pos) / (maxval > 255 ? 2 * size_t(img.width) : size_t(img.width))) +
                              " more rows of " + std::to_string(img.width) + ")"
                        : std::string("")));
  return img;
}

GrayImage read_image(const std::string& path) {
  std::string ext = lower(std::filesystem::path(path).extension().string());
  if (ext == ".pgm") return read_pgm(slurp(path), path);
  if (ext != ".png") fail(path + ": image: unsupported format '" + ext + "' (use .pgm or .png)");
  check_input_file(path);
  png_image im;
  std::memset(&im, 0, sizeof im);
  im.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&im, path.c_str())) fail(path + ": PNG: " + im.message);
  im.format = PNG_FORMAT_RGBA;
  if (size_t(im.width) * im.height > (size_t(1) << 30)) {
    png_image_free(&im);
    fail(path + ": PNG: image too large");
  }
  std::vector<uint8_t> buf(PNG_IMAGE_SIZE(im));
  if (!png_image_finish_read(&im, nullptr, buf.data(), 0, nullptr)) {
    const std::string msg = im.message;
    png_image_free(&im);
    fail(path + ": PNG: " + msg);
  }
  GrayImage img;
  img.width = int(im.width);
  img.height = int(im.height);
  const size_t n = size_t(img.width) * img.height;
  img.value.resize(n);
  img.alpha.resize(n);
  bool any_alpha = false;
  for (size_t k = 0; k < n; ++k) {
    const uint8_t* p = &buf[4 * k];
    img.value[k] = uint8_t((int(p[0]) + p[1] + p[2]) / 3);  // map_server: the mean of the colour channels
    img.alpha[k] = p[3];
    any_alpha |= p[3] != 255;
  }
  if (!any_alpha) img.alpha.clear();
  return img;
}

OccupancyGrid occupancy_from_image(const GrayImage& img, const MapYaml& y, const std::string& source) {
  OccupancyGrid g;
  g.width = img.width;
  g.height = img.height;
  g.resolution = y.resolution;
  g.origin_x = y.origin_x;
  g.origin_y = y.origin_y;
  g.origin_yaw = y.origin_yaw;
  // trinary / scale: only the 100s are occupied (scale's 1..99 lie between the thresholds); raw: the percentage.
  g.occupied_thresh = y.mode == OccupancyMode::kRaw ? y.occupied_thresh : 0.995;
  g.yaml_occupied_thresh = y.occupied_thresh;
  g.source = source;
  g.data.assign(size_t(g.width) * g.height, -1);
  for (int row = 0; row < img.height; ++row)
    for (int i = 0; i < img.width; ++i) {
      const size_t k = size_t(row) * img.width + i;
      const int j = img.height - 1 - row;  // the image's top row is the map's last
      const double mean = img.value[k];
      int8_t v;
      if (y.mode == OccupancyMode::kRaw) {
        v = mean <= 100 ? int8_t(mean) : int8_t(-1);
      } else {
        const double p = y.negate ? mean / 255.0 : (255.0 - mean) / 255.0;
        if (y.mode == OccupancyMode::kScale && !img.alpha.empty() && img.alpha[k] < 255) v = -1;
        else if (p > y.occupied_thresh) v = 100;
        else if (p < y.free_thresh) v = 0;
        else if (y.mode == OccupancyMode::kScale)
          v = int8_t(std::clamp(1 + std::lround(98 * (p - y.free_thresh) / (y.occupied_thresh - y.free_thresh)), 1L, 99L));
        else v = -1;
      }
      g.data[size_t(j) * g.width + i] = v;
    }
  return g;
}

OccupancyGrid read_occupancy_map(const std::string& yaml_path) {
  const MapYaml y = read_map_yaml(yaml_path);
  if (!std::filesystem::exists(y.image_path)) fail(yaml_path + ": image: file '" + y.image_path + "' not found");
  try {
    check_input_file(y.image_path);
  } catch (const std::exception& e) {
    fail(yaml_path + ": image: " + e.what());
  }
  return occupancy_from_image(read_image(y.image_path), y, yaml_path);
}

namespace {

double point_segment(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d d = b - a;
  const double l2 = d.squaredNorm();
  const double t = l2 > 0 ? std::clamp((p - a).dot(d) / l2, 0.0, 1.0) : 0.0;
  return (p - (a + t * d)).norm();
}

// Douglas-Peucker (iterative) over pts[b..e]: marks kept points.
void douglas_peucker(const std::vector<Eigen::Vector2d>& pts, double eps, std::vector<uint8_t>& keep) {
  keep.assign(pts.size(), 0);
  keep.front() = keep.back() = 1;
  std::vector<std::pair<size_t, size_t>> stack{{0, pts.size() - 1}};
  while (!stack.empty()) {
    auto [b, e] = stack.back();
    stack.pop_back();
    if (e <= b + 1) continue;
    double best = -1;
    size_t bi = b;
    for (size_t k = b + 1; k < e; ++k) {
      const double d = point_segment(pts[k], pts[b], pts[e]);
      if (d > best) best = d, bi = k;
    }
    if (best > eps) {
      keep[bi] = 1;
      stack.push_back({b, bi});
      stack.push_back({bi, e});
    }
  }
}

}  // namespace

FloorPlan vectorise_occupancy(const OccupancyGrid& g, const VectoriseOptions& o, VectoriseStats* stats) {
  VectoriseStats st;
  FloorPlan plan;
  const int layer = plan.layer_index("occupied");
  const int W = g.width, H = g.height;
  auto occ = [&](int i, int j) { return i >= 0 && j >= 0 && i < W && j < H && g.occupied(i, j); };
  std::vector<uint8_t> boundary(size_t(W) * H, 0);
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W; ++i) {
      if (!occ(i, j)) continue;
      ++st.occupied_cells;
      if (!occ(i - 1, j) || !occ(i + 1, j) || !occ(i, j - 1) || !occ(i, j + 1)) {
        boundary[size_t(j) * W + i] = 1;
        ++st.boundary_cells;
      }
    }
  // 4-neighbours first, then diagonals.
  static const int kDi[8] = {1, 0, -1, 0, 1, -1, -1, 1}, kDj[8] = {0, 1, 0, -1, 1, 1, -1, -1};
  auto is_free_boundary = [&](int i, int j) {
    return i >= 0 && j >= 0 && i < W && j < H && boundary[size_t(j) * W + i] == 1;
  };
  auto degree = [&](int i, int j) {
    int d = 0;
    for (int k = 0; k < 8; ++k) d += is_free_boundary(i + kDi[k], j + kDj[k]);
    return d;
  };
  const double eps = o.tolerance_cells * g.resolution;
  double err_sum = 0;
  std::vector<Eigen::Vector2d> pts;
  std::vector<uint8_t> keep;
  // Two passes: chains from their ends (cells with at most one unvisited neighbour) first, then loops.
  for (int pass = 0; pass < 2; ++pass)
    for (int j = 0; j < H; ++j)
      for (int i = 0; i < W; ++i) {
        if (!is_free_boundary(i, j) || (pass == 0 && degree(i, j) > 1)) continue;
        pts.clear();
        int ci = i, cj = j, dir = -1;
        for (;;) {
          boundary[size_t(cj) * W + ci] = 2;
          pts.push_back(g.cell_centre(ci, cj));
          // The walk keeps its direction while it can: in a wall two cells thick every cell is a boundary cell,
          // and a fixed neighbour order alone zigzags through both columns (a segment per cell).
          int next = dir >= 0 && is_free_boundary(ci + kDi[dir], cj + kDj[dir]) ? dir : -1;
          for (int k = 0; k < 8 && next < 0; ++k)
            if (is_free_boundary(ci + kDi[k], cj + kDj[k])) next = k;
          if (next < 0) break;
          ci += kDi[next];
          cj += kDj[next];
          dir = next;
        }
        ++st.chains;
        if (pts.size() == 1) {
          const double c = std::cos(g.origin_yaw), s = std::sin(g.origin_yaw);
          const Eigen::Vector2d h(0.05 * g.resolution * c, 0.05 * g.resolution * s);  // a point, non-degenerate
          plan.elements.push_back(Element::segment(pts[0] - h, pts[0] + h, layer));
          ++st.segments;
          continue;
        }
        douglas_peucker(pts, eps, keep);
        size_t prev = 0;
        for (size_t k = 1; k < pts.size(); ++k) {
          if (!keep[k]) continue;
          plan.elements.push_back(Element::segment(pts[prev], pts[k], layer));
          ++st.segments;
          for (size_t q = prev; q <= k; ++q) {
            const double d = point_segment(pts[q], pts[prev], pts[k]);
            if (q > prev || prev == 0) {
              err_sum += d;
              st.max_error_m = std::max(st.max_error_m, d);
            }
          }
          prev = k;
        }
      }
  st.mean_error_m = st.boundary_cells ? err_sum / double(st.boundary_cells) : 0.0;
  plan.source = g.source;
  if (stats) *stats = st;
  return plan;
}

void require_occupied_cells(const OccupancyGrid& g, const FloorPlan& vectorised, const std::string& yaml_path) {
  if (!vectorised.elements.empty()) return;
  // The YAML's threshold, not the grid's internal one (trinary / scale keep only the 100s: 0.995, which the user
  // never wrote and the message used to show).
  std::ostringstream t;
  t << g.yaml_occupied_thresh;
  fail(yaml_path + ": image: no occupied cells (no pixel above occupied_thresh " + t.str() +
       " of the YAML): an all-free or all-unknown map has no walls to localize against");
}

FloorPlan load_occupancy_plan(const std::string& yaml_path, VectoriseStats* stats) {
  const OccupancyGrid g = read_occupancy_map(yaml_path);
  FloorPlan plan = vectorise_occupancy(g, {}, stats);
  require_occupied_cells(g, plan, yaml_path);
  plan.source = yaml_path;
  return plan;
}

}  // namespace fploc
