// JSON and DXF output of a plan diff.
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <ostream>
#include <sstream>

#include "fploc/core/text_out.h"
#include "fploc/plandiff/plan_diff.h"

namespace fploc::plandiff {

void write_json(const Diff& d, const FloorPlan& plan, std::ostream& out, bool all_elements) {
  nlohmann::json j;
  j["frames"] = d.frames;
  j["evidence_frames"] = d.evidence_frames;
  j["plan"] = plan.source;
  j["summary"] = {{"seen", d.count(Status::kSeen)},
                  {"missing", d.count(Status::kMissing)},
                  {"moved", d.count(Status::kMoved)},
                  {"unobserved", d.count(Status::kUnobserved)},
                  {"new", d.added.size()},
                  {"low", d.low.size()},
                  {"missing_parts", d.missing_parts.size()}};
  j["scale"] = {{"error", d.scale_error}, {"sigma", d.scale_sigma}, {"points", d.scale_points}};
  auto& el = j["elements"] = nlohmann::json::array();
  for (const auto& e : d.elements) {
    if (!all_elements && e.status == Status::kSeen) continue;
    const Element& p = plan.elements[size_t(e.id)];
    nlohmann::json o{{"id", e.id},
                     {"status", status_name(e.status)},
                     {"offset_m", e.offset_m},
                     {"offset_spread_m", e.offset_spread_m},
                     {"offset_sigma_m", e.offset_sigma_m},
                     {"pose_sigma_m", e.pose_sigma_m},
                     {"half_offset_m", {e.half_offset_m[0], e.half_offset_m[1]}},
                     {"half_frames", {e.half_frames[0], e.half_frames[1]}},
                     {"seen_ratio", e.seen_ratio()},
                     {"frames_expected", e.frames_expected},
                     {"frames_with_points", e.frames_with_points}};
    if (p.kind == ElementKind::kSegment) {
      o["a"] = {p.a.x(), p.a.y()};
      o["b"] = {p.b.x(), p.b.y()};
    } else {
      o["c"] = {p.c.x(), p.c.y()};
      o["r"] = p.r;
    }
    el.push_back(o);
  }
  // Heights: checked when some evidence scan came with the segmenter's 3D points (else every run is a new wall,
  // "height": "unknown").
  j["heights_checked"] = d.height_frames > 0;
  j["height_frames"] = d.height_frames;
  auto runs = [](const std::vector<NewStructure>& v) {
    nlohmann::json a = nlohmann::json::array();
    for (const auto& n : v)
      a.push_back({{"a", {n.a.x(), n.a.y()}}, {"b", {n.b.x(), n.b.y()}}, {"length_m", n.length()}, {"cells", n.cells},
                   {"min_frames", n.min_frames}, {"rms_m", n.rms_m}, {"extends", n.extends},
                   {"height", height_name(n.height)},
                   {"top_m", std::isfinite(n.top_m) ? nlohmann::json(n.top_m) : nlohmann::json(nullptr)}});
    return a;
  };
  j["new"] = runs(d.added);
  j["low"] = runs(d.low);
  auto& rf = j["refined"] = nlohmann::json::array();
  for (const auto& r : d.refined)
    rf.push_back({{"id", r.element}, {"offset_a", r.offset_a}, {"offset_b", r.offset_b}, {"frames", r.frames}});
  auto& mp = j["missing_parts"] = nlohmann::json::array();
  for (const auto& m : d.missing_parts)
    mp.push_back({{"id", m.element}, {"a", {m.a.x(), m.a.y()}}, {"b", {m.b.x(), m.b.y()}}, {"length_m", m.length()},
                  {"seen_ratio", m.expected ? double(m.seen) / double(m.expected) : 0.0},
                  {"through_ratio", m.expected ? double(m.through) / double(m.expected) : 0.0}});
  out << fploc::json_text(j, 1) << "\n";
}

namespace {

std::string xy(const Eigen::Vector2d& p) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(2) << "(" << p.x() << ", " << p.y() << ")";
  return s.str();
}

}  // namespace

void write_text(const Diff& d, const FloorPlan& plan, std::ostream& out) {
  std::ostringstream o;
  o << std::fixed;
  const size_t parts = d.missing_parts.size();
  o << d.count(Status::kSeen) << " seen, " << d.count(Status::kMissing) << " missing, " << d.count(Status::kMoved)
    << " moved, " << d.count(Status::kUnobserved) << " unobserved, " << d.added.size() << " new, " << d.low.size()
    << " low, " << parts
    << (parts == 1 ? " missing part" : " missing parts") << "; drawing scale ";
  if (d.scale_points > 0)
    o << std::showpos << std::setprecision(2) << 100 * d.scale_error << std::noshowpos << " % +- " << 100 * d.scale_sigma
      << " % (" << d.scale_points << " points)\n";
  else
    o << "too little to tell\n";
  auto layer = [&](const Element& e) {
    return e.layer >= 0 && size_t(e.layer) < plan.layers.size() ? " (" + plan.layers[size_t(e.layer)] + ")" : std::string();
  };
  auto length = [](const Element& e) { return e.kind == ElementKind::kSegment ? (e.b - e.a).norm() : 2 * M_PI * e.r; };
  for (const auto& e : d.elements) {
    if (e.status != Status::kMissing && e.status != Status::kMoved) continue;
    if (e.id < 0 || size_t(e.id) >= plan.elements.size()) continue;
    const Element& p = plan.elements[size_t(e.id)];
    o << "  element " << e.id << layer(p) << ": " << status_name(e.status);
    if (e.status == Status::kMoved)
      o << " " << std::showpos << std::setprecision(3) << e.offset_m << std::noshowpos << " m (+- " << e.offset_sigma_m << ")";
    else
      o << ", seen " << std::setprecision(0) << 100 * e.seen_ratio() << " % of " << e.probes_expected << " expected looks";
    o << ", length " << std::setprecision(2) << length(p) << " m, "
      << (p.kind == ElementKind::kSegment ? xy(p.a) + "-" + xy(p.b) : "centre " + xy(p.c)) << "\n";
  }
  for (const auto& m : d.missing_parts) {
    o << "  element " << m.element;
    if (m.element >= 0 && size_t(m.element) < plan.elements.size()) o << layer(plan.elements[size_t(m.element)]);
    o << ": missing part " << std::setprecision(2) << m.length() << " m, " << xy(m.a) << "-" << xy(m.b)
      << ", seen through " << std::setprecision(0) << (m.expected ? 100.0 * double(m.through) / double(m.expected) : 0.0)
      << " % of " << m.expected << " expected looks\n";
  }
  for (const auto& n : d.added) {
    o << "  new: " << std::setprecision(2) << n.length() << " m, " << xy(n.a) << "-" << xy(n.b);
    if (n.extends >= 0) o << ", extends element " << n.extends;
    if (std::isfinite(n.top_m)) o << ", top " << std::setprecision(2) << n.top_m << " m";
    if (d.height_frames > 0 && n.height == Height::kUnknown) o << ", height not told";
    o << "\n";
  }
  for (const auto& n : d.low)
    o << "  low structure (not a wall): " << std::setprecision(2) << n.length() << " m, " << xy(n.a) << "-" << xy(n.b)
      << ", top " << n.top_m << " m\n";
  if (d.height_frames == 0 && !d.added.empty())
    o << "  (heights not checked: no 3D wall points (FPLOC_SEGMENTS) came with the scans, or the check is off; a new run may be furniture)\n";
  out << o.str();
}

namespace {

void pair(std::ostream& o, int code, const std::string& v) { o << code << "\n" << v << "\n"; }
void num(std::ostream& o, int code, double v) {
  std::ostringstream s;
  s << std::setprecision(10) << v;
  pair(o, code, s.str());
}

void entity(std::ostream& o, const Element& e, const char* layer, const Eigen::Vector2d& shift = Eigen::Vector2d::Zero(),
            double dr = 0) {
  if (e.kind == ElementKind::kSegment) {
    pair(o, 0, "LINE");
    pair(o, 8, layer);
    num(o, 10, e.a.x() + shift.x());
    num(o, 20, e.a.y() + shift.y());
    num(o, 30, 0);
    num(o, 11, e.b.x() + shift.x());
    num(o, 21, e.b.y() + shift.y());
    num(o, 31, 0);
  } else {
    pair(o, 0, e.kind == ElementKind::kCircle ? "CIRCLE" : "ARC");
    pair(o, 8, layer);
    num(o, 10, e.c.x());
    num(o, 20, e.c.y());
    num(o, 30, 0);
    num(o, 40, std::max(1e-3, e.r + dr));
    if (e.kind == ElementKind::kArc) {
      num(o, 50, e.a0 * 180 / M_PI);
      num(o, 51, e.a1 * 180 / M_PI);
    }
  }
}

// A change's label as a DXF TEXT entity (R12: insertion point, height, value) on the change's layer, beside the
// middle of its line: CAD programs show it, the project's reader ignores it (it reads geometry only). `at`: the
// line's middle; the text sits a little above it, `h` metres high.
void label(std::ostream& o, const std::string& text, const char* layer, const Eigen::Vector2d& at, double h) {
  pair(o, 0, "TEXT");
  pair(o, 8, layer);
  num(o, 10, at.x());
  num(o, 20, at.y() + 0.3 * h);
  num(o, 30, 0);
  num(o, 40, h);
  pair(o, 1, text);
}

std::string metres(double v, int digits, bool sign = false) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << (sign ? std::showpos : std::noshowpos) << v << std::noshowpos << " m";
  return s.str();
}

}  // namespace

void write_dxf(const Diff& d, const FloorPlan& plan, std::ostream& o) {
  struct L {
    const char* name;
    int color;
  };
  const L layers[] = {{"0", 7}, {"FPLOC-PLAN", 8}, {"FPLOC-MISSING", 1}, {"FPLOC-MOVED", 2}, {"FPLOC-NEW", 3}, {"FPLOC-LOW", 4}};
  pair(o, 0, "SECTION");
  pair(o, 2, "HEADER");
  pair(o, 9, "$ACADVER");
  pair(o, 1, "AC1009");
  pair(o, 9, "$INSUNITS");
  pair(o, 70, "6");
  pair(o, 0, "ENDSEC");
  pair(o, 0, "SECTION");
  pair(o, 2, "TABLES");
  pair(o, 0, "TABLE");
  pair(o, 2, "LTYPE");
  pair(o, 70, "1");
  pair(o, 0, "LTYPE");
  pair(o, 2, "CONTINUOUS");
  pair(o, 70, "0");
  pair(o, 3, "Solid line");
  pair(o, 72, "65");
  pair(o, 73, "0");
  num(o, 40, 0);
  pair(o, 0, "ENDTAB");
  pair(o, 0, "TABLE");
  pair(o, 2, "LAYER");
  pair(o, 70, std::to_string(std::size(layers)));
  for (const auto& l : layers) {
    pair(o, 0, "LAYER");
    pair(o, 2, l.name);
    pair(o, 70, "0");
    pair(o, 62, std::to_string(l.color));
    pair(o, 6, "CONTINUOUS");
  }
  pair(o, 0, "ENDTAB");
  pair(o, 0, "ENDSEC");
  pair(o, 0, "SECTION");
  pair(o, 2, "ENTITIES");
  for (const auto& e : plan.elements) entity(o, e, "FPLOC-PLAN");
  for (const auto& e : d.elements) {
    const Element& p = plan.elements[size_t(e.id)];
    if (e.status == Status::kMissing) entity(o, p, "FPLOC-MISSING");
    if (e.status == Status::kMoved) {
      if (p.kind == ElementKind::kSegment) {
        const Eigen::Vector2d u = (p.b - p.a).normalized();
        entity(o, p, "FPLOC-MOVED", e.offset_m * Eigen::Vector2d(-u.y(), u.x()));
      } else {
        entity(o, p, "FPLOC-MOVED", Eigen::Vector2d::Zero(), e.offset_m);
      }
    }
  }
  for (const auto& m : d.missing_parts) entity(o, Element::segment(m.a, m.b), "FPLOC-MISSING");
  for (const auto& n : d.added) entity(o, Element::segment(n.a, n.b), "FPLOC-NEW");
  for (const auto& n : d.low) entity(o, Element::segment(n.a, n.b), "FPLOC-LOW");
  // Each change's label (what the terminal and the JSON say: "moved +0.115 m", "missing 7.50 m"), a text height of
  // 1/80 of the plan's larger side (0.15 m to 1 m).
  const double h = std::clamp(plan.bounds().size().maxCoeff() / 80, 0.15, 1.0);
  auto length = [](const Element& e) { return e.kind == ElementKind::kSegment ? (e.b - e.a).norm() : 2 * M_PI * e.r; };
  for (const auto& e : d.elements) {
    if (e.status != Status::kMissing && e.status != Status::kMoved) continue;
    if (e.id < 0 || size_t(e.id) >= plan.elements.size()) continue;
    const Element& p = plan.elements[size_t(e.id)];
    Eigen::Vector2d mid = p.kind == ElementKind::kSegment ? Eigen::Vector2d(0.5 * (p.a + p.b)) : Eigen::Vector2d(p.c + Eigen::Vector2d(0, p.r));
    if (e.status == Status::kMoved && p.kind == ElementKind::kSegment) {
      const Eigen::Vector2d u = (p.b - p.a).normalized();
      mid += e.offset_m * Eigen::Vector2d(-u.y(), u.x());
    }
    const std::string id = "element " + std::to_string(e.id) + ": ";
    if (e.status == Status::kMoved) label(o, id + "moved " + metres(e.offset_m, 3, true), "FPLOC-MOVED", mid, h);
    else label(o, id + "missing " + metres(length(p), 2), "FPLOC-MISSING", mid, h);
  }
  for (const auto& m : d.missing_parts)
    label(o, "element " + std::to_string(m.element) + ": missing part " + metres(m.length(), 2), "FPLOC-MISSING",
          0.5 * (m.a + m.b), h);
  for (const auto& n : d.added) label(o, "new " + metres(n.length(), 2), "FPLOC-NEW", 0.5 * (n.a + n.b), h);
  for (const auto& n : d.low)
    label(o, "low " + metres(n.length(), 2) + (std::isfinite(n.top_m) ? ", top " + metres(n.top_m, 2) : std::string()),
          "FPLOC-LOW", 0.5 * (n.a + n.b), h);
  pair(o, 0, "ENDSEC");
  pair(o, 0, "EOF");
}

}  // namespace fploc::plandiff
