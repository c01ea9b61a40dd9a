// A focused ASCII DXF reader for floor plans (see dxf.h for what it reads and why it exists).
#include "fploc/floorplan/dxf.h"

#include <iconv.h>

#include <Eigen/Dense>
#include <cerrno>
#include <cstdio>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <iostream>
#include <map>
#include <set>
#include <stdexcept>
#include <unordered_map>

namespace fploc {
namespace {

[[noreturn]] void fail(const std::string& m) { throw std::runtime_error(m); }

// Double -> int without undefined behaviour (clamped; NaN -> lo).
int to_int(double v, int lo, int hi) {
  if (!(v >= lo)) return lo;
  if (v >= hi) return hi;
  return int(v);
}
constexpr int kBig = 1 << 30;

// Sweep in (0, 2 pi] (no loops: angles in a fuzzed file can be huge).
double norm_sweep(double s) {
  if (!std::isfinite(s)) return 2 * M_PI;
  s = std::fmod(s, 2 * M_PI);
  if (s <= 0) s += 2 * M_PI;
  return s;
}

struct Group {
  int code;
  std::string value;
  int line;  // line number of the group code
};

struct Entity {
  std::string type;
  int line = 0;
  std::vector<Group> groups;
  std::vector<Entity> children;  // VERTEX entities of a POLYLINE
};

struct Block {
  std::string name;
  Eigen::Vector2d base{0, 0};
  std::vector<Entity> entities;
};

std::string upper(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::toupper(c); });
  return s;
}

std::string trim(const std::string& s) {
  size_t b = 0, e = s.size();
  while (b < e && (s[b] == ' ' || s[b] == '\t' || s[b] == '\r')) ++b;
  while (e > b && (s[e - 1] == ' ' || s[e - 1] == '\t' || s[e - 1] == '\r')) --e;
  return s.substr(b, e - b);
}

// Decodes \U+XXXX escapes (older DXF) to UTF-8.
std::string decode_unicode(const std::string& s) {
  if (s.find("\\U+") == std::string::npos && s.find("\\u+") == std::string::npos) return s;
  std::string out;
  for (size_t i = 0; i < s.size();) {
    if (i + 7 <= s.size() && s[i] == '\\' && (s[i + 1] == 'U' || s[i + 1] == 'u') && s[i + 2] == '+') {
      unsigned cp = 0;
      auto r = std::from_chars(s.data() + i + 3, s.data() + i + 7, cp, 16);
      if (r.ec == std::errc() && r.ptr == s.data() + i + 7) {
        if (cp < 0x80) {
          out += char(cp);
        } else if (cp < 0x800) {
          out += char(0xC0 | (cp >> 6));
          out += char(0x80 | (cp & 0x3F));
        } else {
          out += char(0xE0 | (cp >> 12));
          out += char(0x80 | ((cp >> 6) & 0x3F));
          out += char(0x80 | (cp & 0x3F));
        }
        i += 7;
        continue;
      }
    }
    out += s[i++];
  }
  return out;
}

class Reader {
 public:
  Reader(const std::string& text, const std::string& source) : text_(text), source_(source) {}

  // Next (code, value) pair; false at the end of the text.
  bool next(Group* g) {
    if (pushed_) {
      *g = pushed_group_;
      pushed_ = false;
      return true;
    }
    std::string code_line, value_line;
    if (!line(&code_line)) return false;
    const int code_lineno = lineno_;
    if (!line(&value_line))
      fail(source_ + ":" + std::to_string(code_lineno) + ": truncated DXF (group code without a value)");
    const std::string c = trim(code_line);
    int code = 0;
    auto r = std::from_chars(c.data(), c.data() + c.size(), code);
    if (c.empty() || r.ec != std::errc() || r.ptr != c.data() + c.size())
      fail(source_ + ":" + std::to_string(code_lineno) + ": expected a DXF group code, got '" + c.substr(0, 40) + "'");
    g->code = code;
    g->value = trim(value_line);
    g->line = code_lineno;
    return true;
  }
  void push_back(const Group& g) {
    pushed_group_ = g;
    pushed_ = true;
  }
  int lineno() const { return lineno_; }

 private:
  bool line(std::string* out) {
    if (pos_ >= text_.size()) return false;
    size_t e = text_.find('\n', pos_);
    if (e == std::string::npos) e = text_.size();
    out->assign(text_, pos_, e - pos_);
    pos_ = e + 1;
    ++lineno_;
    return true;
  }
  const std::string& text_;
  std::string source_;
  size_t pos_ = 0;
  int lineno_ = 0;
  bool pushed_ = false;
  Group pushed_group_;
};

// 2D affine transform p -> A p + t.
struct Xf {
  Eigen::Matrix2d A = Eigen::Matrix2d::Identity();
  Eigen::Vector2d t = Eigen::Vector2d::Zero();
  Eigen::Vector2d operator()(const Eigen::Vector2d& p) const { return A * p + t; }
  Xf operator*(const Xf& o) const { return {A * o.A, A * o.t + t}; }
};

struct Provenance {
  std::string type;
  int line;
};

// iconv's name for a $DWGCODEPAGE value: ANSI_1252 -> CP1252, DOS850 -> CP850, ISO8859-1 -> ISO-8859-1, ...
std::string iconv_codepage(const std::string& dxf) {
  const std::string u = upper(dxf);
  if (u.rfind("ANSI_", 0) == 0) return "CP" + u.substr(5);
  if (u.rfind("DOS", 0) == 0 && u.size() > 3 && std::isdigit((unsigned char)u[3])) return "CP" + u.substr(3);
  if (u.rfind("ISO8859", 0) == 0 && u.size() > 8) return "ISO-8859-" + u.substr(8);
  if (u == "UTF8" || u == "UTF-8") return "UTF-8";
  if (u == "MAC-ROMAN") return "MACINTOSH";
  if (u == "KSC5601") return "EUC-KR";
  return u;  // BIG5, GB2312, JOHAB, ... as iconv knows them
}

// Text of a DXF (layer and block names) to UTF-8. Before R2007 ($ACADVER < AC1021) text is in $DWGCODEPAGE;
// from R2007 on it is UTF-8, but writers that declare AC1027 and still write the code page exist (a layer
// 'W\xe4nde' in an ANSI_1252 file): text that is not valid UTF-8 is then read in $DWGCODEPAGE. Without a code
// page: UTF-8. Bytes that convert in neither are escaped as \xNN. ASCII strings (nearly all) take no
// conversion; others are converted once.
class TextDecoder {
 public:
  TextDecoder() = default;
  TextDecoder(const TextDecoder&) = delete;
  TextDecoder& operator=(const TextDecoder&) = delete;
  ~TextDecoder() {
    for (iconv_t cd : {utf8_, cp_})
      if (cd != iconv_t(-1)) iconv_close(cd);
  }
  void setup(const std::string& codepage, const std::string& acadver) {
    codepage_ = codepage;
    unicode_ = codepage.empty() || acadver >= "AC1021";
    utf8_ = iconv_open("UTF-8", "UTF-8");
    if (codepage.empty()) return;
    const std::string from = iconv_codepage(codepage);
    if (from == "UTF-8") {
      unicode_ = true;
      return;
    }
    cp_ = iconv_open("UTF-8", from.c_str());
    if (cp_ == iconv_t(-1)) unknown_ = true;
  }
  std::string operator()(const std::string& raw) {
    bool ascii = true;
    for (unsigned char c : raw)
      if (c >= 0x80) {
        ascii = false;
        break;
      }
    if (ascii) return decode_unicode(raw);
    auto it = cache_.find(raw);
    if (it != cache_.end()) return it->second;
    std::string out;
    bool ok;
    if (unicode_) {
      ok = convert(utf8_, raw, &out);
      if (!ok && cp_ != iconv_t(-1) && (ok = convert(cp_, raw, &out))) read_in_codepage_ = true;
    } else {
      ok = cp_ != iconv_t(-1) && convert(cp_, raw, &out);  // an unknown code page: escaped
    }
    if (!ok) {
      convert(iconv_t(-1), raw, &out);
      escaped_ = true;
    }
    out = decode_unicode(out);
    cache_.emplace(raw, out);
    return out;
  }
  // What to warn about after the read ("" = nothing).
  std::string warning(const std::string& acadver) const {
    if (escaped_ && unknown_)
      return "unknown code page $DWGCODEPAGE '" + codepage_ + "': non-ASCII bytes in layer and block names are shown as \\xNN";
    if (escaped_)
      return std::string("layer or block names that are not text in ") +
             (codepage_.empty() ? "UTF-8" : "UTF-8 nor $DWGCODEPAGE " + codepage_) + ": the bytes are shown as \\xNN";
    if (read_in_codepage_)
      return "layer or block names are not UTF-8 as $ACADVER " + acadver + " says; read them as $DWGCODEPAGE " + codepage_;
    return "";
  }

 private:
  // raw -> *out with `cd`; false at the first byte that does not convert. cd = -1: escape every non-ASCII byte.
  bool convert(iconv_t cd, const std::string& in, std::string* out) {
    out->clear();
    if (cd == iconv_t(-1)) {
      for (unsigned char c : in) {
        if (c < 0x80) {
          *out += char(c);
          continue;
        }
        char e[8];
        std::snprintf(e, sizeof e, "\\x%02X", c);
        *out += e;
      }
      return true;
    }
    iconv(cd, nullptr, nullptr, nullptr, nullptr);
    char* ip = const_cast<char*>(in.data());
    size_t il = in.size();
    char buf[512];
    while (il > 0) {
      char* op = buf;
      size_t ol = sizeof buf;
      const size_t r = iconv(cd, &ip, &il, &op, &ol);
      out->append(buf, size_t(op - buf));
      if (r == size_t(-1) && errno != E2BIG) return false;  // EILSEQ / EINVAL: not text in this encoding
    }
    char* op = buf;
    size_t ol = sizeof buf;
    iconv(cd, nullptr, nullptr, &op, &ol);
    out->append(buf, size_t(op - buf));
    return true;
  }
  iconv_t utf8_ = iconv_t(-1), cp_ = iconv_t(-1);
  std::string codepage_;
  bool unicode_ = true, unknown_ = false, escaped_ = false, read_in_codepage_ = false;
  std::unordered_map<std::string, std::string> cache_;
};

class DxfLoader {
 public:
  DxfLoader(const std::string& source, const PlanLoadOptions& o) : source_(source), o_(o) {}

  FloorPlan load(const std::string& text, DxfStats* stats) {
    if (text.rfind("AutoCAD Binary DXF", 0) == 0)
      fail(source_ + ": binary DXF is not supported; save the drawing as ASCII DXF");
    parse(text);
    text_.setup(codepage_, acadver_);
    // Units.
    double unit = 1.0;
    std::string unit_name = "m (default)";
    static const std::map<int, std::pair<double, const char*>> kUnits = {
        {0, {1.0, "unitless -> m"}}, {1, {0.0254, "in"}}, {2, {0.3048, "ft"}}, {4, {0.001, "mm"}},
        {5, {0.01, "cm"}},           {6, {1.0, "m"}},      {7, {1000.0, "km"}}, {14, {0.1, "dm"}}};
    if (insunits_ >= 0) {
      auto it = kUnits.find(insunits_);
      if (it != kUnits.end()) {
        unit = it->second.first;
        unit_name = std::string(it->second.second) + " ($INSUNITS " + std::to_string(insunits_) + ")";
      } else {
        unit_name = "m ($INSUNITS " + std::to_string(insunits_) + " not supported, assuming metres)";
      }
    }
    if (!o_.units_override.empty()) {
      unit = metres_per_unit(o_.units_override);
      unit_name = o_.units_override + " (override)";
    }
    unit_ = unit;
    tol_ = std::max(o_.curve_tolerance, 1e-6) / unit;

    for (const auto& e : entities_) emit_entity(e, Xf{}, "", 0, e);
    plan_.source = source_;
    if (plan_.elements.empty()) {
      if (!o_.layer_globs.empty() && !layers_seen_.empty()) {
        std::string g, l;
        for (const auto& s : o_.layer_globs) g += (g.empty() ? "" : ",") + s;
        int k = 0;
        for (const auto& [name, n] : layers_seen_) {
          if (k++ == 40) {
            l += ", ...";
            break;
          }
          l += (l.empty() ? "" : ", ") + name + " (" + std::to_string(n) + ")";
        }
        fail(source_ + ": no elements on layers matching '" + g + "' (layers with elements: " + l + ")");
      }
      fail(source_ + ": no supported entities (LINE, LWPOLYLINE, POLYLINE, CIRCLE, ARC, ELLIPSE, SPLINE, INSERT)");
    }
    drop_outliers();
    scale_plan(plan_, unit);
    if (!o_.quiet)
      if (const std::string w = text_.warning(acadver_); !w.empty()) std::cerr << source_ << ": warning: " << w << "\n";
    if (!o_.quiet) {
      const Box2 b = plan_.bounds();
      std::cerr << source_ << ": " << plan_.elements.size() << " elements from " << entities_.size()
                << " entities (" << inserts_ << " INSERTs expanded), units " << unit_name << ", extents "
                << b.size().x() << " x " << b.size().y() << " m";
      if (!unsupported_.empty()) {
        std::cerr << "; ignored:";
        for (const auto& [t, n] : unsupported_) std::cerr << " " << t << " " << n;
      }
      std::cerr << "\n";
      if (b.size().maxCoeff() > 5000 || b.size().maxCoeff() < 0.5)
        std::cerr << source_ << ": warning: extents of " << b.size().maxCoeff()
                  << " m look wrong for a floor plan; check the units (--units m|cm|mm)\n";
    }
    if (stats) {
      stats->entities_read = int(entities_.size());
      stats->elements = int(plan_.elements.size());
      stats->inserts_expanded = inserts_;
      stats->outliers_dropped = dropped_;
      int u = 0;
      for (const auto& [t, n] : unsupported_) u += n;
      stats->unsupported = u;
      stats->unit_scale = unit;
    }
    return std::move(plan_);
  }

 private:
  // ---- parsing ---------------------------------------------------------------------------------
  void parse(const std::string& text) {
    Reader r(text, source_);
    Group g;
    bool saw_eof = false;
    while (r.next(&g)) {
      if (g.code == 999) continue;
      if (g.code != 0) continue;  // stray group outside a section: tolerate
      if (g.value == "EOF") {
        saw_eof = true;
        break;
      }
      if (g.value != "SECTION")
        fail(source_ + ":" + std::to_string(g.line) + ": expected SECTION, got '" + g.value.substr(0, 40) + "'");
      Group name;
      if (!r.next(&name) || name.code != 2)
        fail(source_ + ":" + std::to_string(g.line) + ": SECTION without a name (truncated DXF?)");
      if (name.value == "HEADER")
        parse_header(r, name.line);
      else if (name.value == "BLOCKS")
        parse_blocks(r, name.line);
      else if (name.value == "ENTITIES")
        parse_entities(r, &entities_, "ENTITIES", name.line, true);
      else
        skip_section(r, name.value, name.line);
    }
    if (!saw_eof && !o_.quiet) std::cerr << source_ << ": note: no EOF marker at the end of the file\n";
  }

  [[noreturn]] void truncated(const std::string& where, int line) {
    fail(source_ + ":" + std::to_string(line) + ": truncated DXF (file ends inside " + where + ")");
  }

  void skip_section(Reader& r, const std::string& name, int line) {
    Group g;
    while (r.next(&g))
      if (g.code == 0 && g.value == "ENDSEC") return;
    truncated("section " + name, line);
  }

  void parse_header(Reader& r, int line) {
    Group g;
    std::string var;
    while (r.next(&g)) {
      if (g.code == 0 && g.value == "ENDSEC") return;
      if (g.code == 9) var = g.value;
      if (var == "$INSUNITS" && g.code == 70) insunits_ = parse_int(g, "HEADER $INSUNITS");
      if (var == "$DWGCODEPAGE" && g.code == 3) codepage_ = g.value;
      if (var == "$ACADVER" && g.code == 1) acadver_ = g.value;
    }
    truncated("section HEADER", line);
  }

  // Reads entities until ENDSEC (or ENDBLK when in_block). The terminating group is consumed.
  void parse_entities(Reader& r, std::vector<Entity>* out, const std::string& where, int line, bool section) {
    Group g;
    if (!r.next(&g)) truncated(where, line);
    while (true) {
      if (g.code != 0) {  // groups before the first entity: skip
        if (!r.next(&g)) truncated(where, line);
        continue;
      }
      if (section && g.value == "ENDSEC") return;
      if (!section && g.value == "ENDBLK") {
        // consume ENDBLK's own groups
        while (r.next(&g))
          if (g.code == 0) {
            r.push_back(g);
            return;
          }
        truncated(where, line);
      }
      if (g.value == "EOF") truncated(where, line);
      Entity e;
      e.type = g.value;
      e.line = g.line;
      bool more = false;
      while ((more = r.next(&g)) && g.code != 0) e.groups.push_back(g);
      if (!more) truncated(where + " (" + e.type + " at line " + std::to_string(e.line) + ")", e.line);
      if (e.type == "POLYLINE") {
        // VERTEX ... SEQEND follow.
        while (g.code == 0 && g.value == "VERTEX") {
          Entity v;
          v.type = "VERTEX";
          v.line = g.line;
          while ((more = r.next(&g)) && g.code != 0) v.groups.push_back(g);
          if (!more) truncated("POLYLINE at line " + std::to_string(e.line), e.line);
          e.children.push_back(std::move(v));
        }
      }
      if (g.code == 0 && g.value == "SEQEND") {
        while ((more = r.next(&g)) && g.code != 0) {
        }
        if (!more) truncated(where, line);
      }
      if (e.type != "SEQEND" && e.type != "ATTRIB") out->push_back(std::move(e));
    }
  }

  void parse_blocks(Reader& r, int line) {
    Group g;
    if (!r.next(&g)) truncated("section BLOCKS", line);
    while (true) {
      if (g.code == 0 && g.value == "ENDSEC") return;
      if (g.code == 0 && g.value == "BLOCK") {
        Block b;
        const int bl = g.line;
        bool more;
        while ((more = r.next(&g)) && g.code != 0) {
          if (g.code == 2) b.name = upper(g.value);
          if (g.code == 10) b.base.x() = parse_num(g, "BLOCK");
          if (g.code == 20) b.base.y() = parse_num(g, "BLOCK");
        }
        if (!more) truncated("BLOCK at line " + std::to_string(bl), bl);
        r.push_back(g);
        parse_entities(r, &b.entities, "BLOCK " + b.name, bl, false);
        blocks_[b.name] = std::move(b);
        if (!r.next(&g)) truncated("section BLOCKS", line);
        continue;
      }
      if (!r.next(&g)) truncated("section BLOCKS", line);
    }
  }

  double parse_num(const Group& g, const std::string& entity) const {
    double v = 0;
    const std::string& s = g.value;
    const char* b = s.data();
    if (!s.empty() && *b == '+') ++b;
    auto r = std::from_chars(b, s.data() + s.size(), v);
    if (s.empty() || r.ec != std::errc() || r.ptr != s.data() + s.size())
      fail(source_ + ":" + std::to_string(g.line) + ": " + entity + ": bad number '" + s.substr(0, 40) +
           "' for group code " + std::to_string(g.code));
    if (!std::isfinite(v))
      fail(source_ + ":" + std::to_string(g.line) + ": " + entity + ": non-finite value '" + s.substr(0, 40) +
           "' for group code " + std::to_string(g.code));
    return v;
  }
  int parse_int(const Group& g, const std::string& entity) const {
    const double v = parse_num(g, entity);
    if (std::abs(v) > 2e9) fail(source_ + ":" + std::to_string(g.line) + ": " + entity + ": integer out of range");
    return int(v);
  }

  // ---- entity helpers --------------------------------------------------------------------------
  std::string where(const Entity& e) const { return source_ + ":" + std::to_string(e.line) + ": " + e.type; }
  double num(const Entity& e, int code, double def) const {
    for (const auto& g : e.groups)
      if (g.code == code) return parse_num(g, e.type);
    return def;
  }
  std::string str(const Entity& e, int code, const std::string& def) const {
    for (const auto& g : e.groups)
      if (g.code == code) return g.value;
    return def;
  }
  Eigen::Vector3d extrusion(const Entity& e) const {
    Eigen::Vector3d n(num(e, 210, 0), num(e, 220, 0), num(e, 230, 1));
    const double len = n.norm();
    if (!(len > 1e-12)) return Eigen::Vector3d(0, 0, 1);
    return n / len;
  }
  // OCS -> WCS (projected on the plan) by the arbitrary-axis algorithm.
  static Xf ocs(const Eigen::Vector3d& n) {
    if (std::abs(n.x()) < 1e-12 && std::abs(n.y()) < 1e-12 && n.z() > 0) return Xf{};
    Eigen::Vector3d ax = (std::abs(n.x()) < 1.0 / 64 && std::abs(n.y()) < 1.0 / 64) ? Eigen::Vector3d::UnitY().cross(n)
                                                                                  : Eigen::Vector3d::UnitZ().cross(n);
    ax.normalize();
    const Eigen::Vector3d ay = n.cross(ax);
    Xf x;
    x.A << ax.x(), ay.x(), ax.y(), ay.y();
    return x;
  }

  // ---- emission --------------------------------------------------------------------------------
  void add(const Element& e0, const Entity& top) {
    if (plan_.elements.size() >= kMaxElements)
      fail(source_ + ": more than " + std::to_string(kMaxElements) + " elements (runaway INSERT nesting?)");
    plan_.elements.push_back(e0);
    prov_.push_back({top.type, top.line});
  }
  void seg(const Xf& x, const Eigen::Vector2d& p, const Eigen::Vector2d& q, int layer, const Entity& top) {
    const Eigen::Vector2d a = x(p), b = x(q);
    if (!a.allFinite() || !b.allFinite()) fail(where(top) + ": non-finite coordinate after transformation");
    if ((a - b).squaredNorm() == 0) return;
    add(Element::segment(a, b, layer), top);
  }
  void polyline(const Xf& x, const std::vector<Eigen::Vector2d>& pts, int layer, const Entity& top) {
    for (size_t i = 1; i < pts.size(); ++i) seg(x, pts[i - 1], pts[i], layer, top);
  }
  int steps_for(double radius, double sweep) const {
    const double r = std::max(radius, 1e-12);
    const double step = tol_ < r ? 2 * std::acos(1 - tol_ / r) : M_PI / 2;
    return to_int(std::ceil(std::abs(sweep) / std::max(step, 1e-4)), 1, 4096);
  }
  // Counter-clockwise arc (local frame) from a0 to a1 (radians); a full circle when full.
  void arc(const Xf& x, const Eigen::Vector2d& c, double r, double a0, double a1, bool full, int layer, const Entity& top) {
    if (!(r > 0)) return;
    const Eigen::Vector2d c0 = x.A.col(0), c1 = x.A.col(1);
    const double s0 = c0.norm(), s1 = c1.norm();
    const bool similar = std::abs(s0 - s1) <= 1e-9 * std::max(s0, s1) && std::abs(c0.dot(c1)) <= 1e-9 * s0 * s1 && s0 > 0;
    const Eigen::Vector2d cc = x(c);
    if (!cc.allFinite()) fail(where(top) + ": non-finite coordinate after transformation");
    if (similar) {
      if (full) {
        add(Element::circle(cc, r * s0, layer), top);
        return;
      }
      const double det = x.A.determinant();
      const Eigen::Vector2d u0 = x.A * Eigen::Vector2d(std::cos(a0), std::sin(a0));
      const Eigen::Vector2d u1 = x.A * Eigen::Vector2d(std::cos(a1), std::sin(a1));
      double b0 = std::atan2(u0.y(), u0.x()), b1 = std::atan2(u1.y(), u1.x());
      if (det < 0) std::swap(b0, b1);
      Element e = Element::arc(cc, r * s0, b0, b1, layer);
      // Keep the sweep (a full-turn arc stays a full turn).
      e.a1 = e.a0 + norm_sweep(a1 - a0);
      add(e, top);
      return;
    }
    // Non-uniform scale: the image is an elliptical arc; approximate by chords.
    const double sweep = full ? 2 * M_PI : norm_sweep(a1 - a0);
    const int n = steps_for(r * std::max(s0, s1), sweep);
    std::vector<Eigen::Vector2d> pts;
    for (int k = 0; k <= n; ++k) {
      const double t = a0 + sweep * k / n;
      pts.push_back(c + r * Eigen::Vector2d(std::cos(t), std::sin(t)));
    }
    polyline(x, pts, layer, top);
  }
  // Bulged polyline vertex list (local frame).
  void bulged(const Xf& x, const std::vector<Eigen::Vector2d>& v, const std::vector<double>& bulge, bool closed, int layer,
              const Entity& top) {
    const size_t n = v.size();
    if (n < 2) return;
    const size_t m = closed ? n : n - 1;
    for (size_t i = 0; i < m; ++i) {
      const Eigen::Vector2d p1 = v[i], p2 = v[(i + 1) % n];
      const double b = bulge[i];
      if (std::abs(b) < 1e-12 || (p2 - p1).norm() == 0) {
        seg(x, p1, p2, layer, top);
        continue;
      }
      const double theta = 4 * std::atan(b);  // signed sweep
      const Eigen::Vector2d d = p2 - p1;
      const double chord = d.norm();
      const Eigen::Vector2d left(-d.y() / chord, d.x() / chord);
      const Eigen::Vector2d c = (p1 + p2) / 2 + left * (chord / 2 / std::tan(theta / 2));
      const double r = chord / (2 * std::abs(std::sin(theta / 2)));
      const double ang1 = std::atan2(p1.y() - c.y(), p1.x() - c.x()), ang2 = std::atan2(p2.y() - c.y(), p2.x() - c.x());
      double a0 = theta > 0 ? ang1 : ang2;
      double sweep = std::abs(theta);
      arc(x, c, r, a0, a0 + sweep, false, layer, top);
    }
  }

  void emit_entity(const Entity& e, const Xf& xf, const std::string& inherited, int depth, const Entity& top) {
    if (++visits_ > kMaxVisits) fail(where(top) + ": more than " + std::to_string(kMaxVisits) + " block entity expansions (runaway INSERT arrays?)");
    if (num(e, 67, 0) != 0) return;  // paper space
    std::string lname = text_(str(e, 8, "0"));
    if (lname == "0" && !inherited.empty()) lname = inherited;
    const std::string& t = e.type;
    if (t == "INSERT") {
      expand_insert(e, xf, lname, depth, top);
      return;
    }
    static const std::set<std::string> kGeom = {"LINE", "LWPOLYLINE", "POLYLINE", "CIRCLE", "ARC", "ELLIPSE", "SPLINE"};
    if (!kGeom.count(t)) {
      ++unsupported_[t];
      return;
    }
    ++layers_seen_[lname];
    if (!layer_selected(o_.layer_globs, lname)) return;
    const int layer = plan_.layer_index(lname);
    if (t == "LINE") {
      seg(xf, {num(e, 10, 0), num(e, 20, 0)}, {num(e, 11, 0), num(e, 21, 0)}, layer, top);
    } else if (t == "CIRCLE" || t == "ARC") {
      const Xf x = xf * ocs(extrusion(e));
      const double r = num(e, 40, 0);
      if (!(r > 0)) fail(where(e) + ": radius must be > 0");
      const Eigen::Vector2d c(num(e, 10, 0), num(e, 20, 0));
      if (t == "CIRCLE")
        arc(x, c, r, 0, 2 * M_PI, true, layer, top);
      else {
        const double a0 = num(e, 50, 0) * M_PI / 180, a1 = num(e, 51, 360) * M_PI / 180;
        arc(x, c, r, a0, a1, false, layer, top);
      }
    } else if (t == "LWPOLYLINE") {
      const Xf x = xf * ocs(extrusion(e));
      std::vector<Eigen::Vector2d> v;
      std::vector<double> bulge;
      for (const auto& g : e.groups) {
        if (g.code == 10) {
          v.push_back({parse_num(g, t), 0});
          bulge.push_back(0);
        } else if (g.code == 20 && !v.empty()) {
          v.back().y() = parse_num(g, t);
        } else if (g.code == 42 && !v.empty()) {
          bulge.back() = parse_num(g, t);
        }
      }
      const bool closed = (to_int(num(e, 70, 0), -kBig, kBig) & 1) != 0;
      bulged(x, v, bulge, closed, layer, top);
    } else if (t == "POLYLINE") {
      const int flags = to_int(num(e, 70, 0), -kBig, kBig);
      if (flags & (16 | 64)) {  // polygon / polyface mesh
        ++unsupported_["POLYLINE(mesh)"];
        return;
      }
      const bool is3d = flags & 8;
      const Xf x = is3d ? xf : xf * ocs(extrusion(e));
      std::vector<Eigen::Vector2d> v;
      std::vector<double> bulge;
      for (const auto& c : e.children) {
        const int vf = to_int(num(c, 70, 0), -kBig, kBig);
        if (vf & 16) continue;  // spline frame control point
        v.push_back({num(c, 10, 0), num(c, 20, 0)});
        bulge.push_back(is3d ? 0.0 : num(c, 42, 0));
      }
      bulged(x, v, bulge, (flags & 1) != 0, layer, top);
    } else if (t == "ELLIPSE") {
      const Eigen::Vector3d n = extrusion(e);
      const Eigen::Vector3d c(num(e, 10, 0), num(e, 20, 0), num(e, 30, 0));
      const Eigen::Vector3d M(num(e, 11, 0), num(e, 21, 0), num(e, 31, 0));
      const double ratio = num(e, 40, 1);
      if (!(M.norm() > 0) || !(ratio > 0) || ratio > 1 + 1e-9) fail(where(e) + ": bad major axis or ratio");
      const Eigen::Vector3d mi = n.cross(M) * ratio;
      double t0 = num(e, 41, 0), t1 = num(e, 42, 2 * M_PI);
      const double sweep = norm_sweep(t1 - t0);
      const int steps = steps_for(M.norm(), sweep);
      std::vector<Eigen::Vector2d> pts;
      for (int k = 0; k <= steps; ++k) {
        const double u = t0 + sweep * k / steps;
        const Eigen::Vector3d p = c + std::cos(u) * M + std::sin(u) * mi;
        pts.push_back(p.head<2>());
      }
      polyline(xf, pts, layer, top);
    } else if (t == "SPLINE") {
      spline(e, xf, layer, top);
    }
  }

  void spline(const Entity& e, const Xf& xf, int layer, const Entity& top) {
    const int degree = to_int(num(e, 71, 3), -kBig, kBig);
    std::vector<double> knots, weights;
    std::vector<Eigen::Vector2d> ctrl, fit;
    for (const auto& g : e.groups) {
      if (g.code == 40) knots.push_back(parse_num(g, e.type));
      if (g.code == 41) weights.push_back(parse_num(g, e.type));
      if (g.code == 10) ctrl.push_back({parse_num(g, e.type), 0});
      if (g.code == 20 && !ctrl.empty()) ctrl.back().y() = parse_num(g, e.type);
      if (g.code == 11) fit.push_back({parse_num(g, e.type), 0});
      if (g.code == 21 && !fit.empty()) fit.back().y() = parse_num(g, e.type);
    }
    const int n = int(ctrl.size());
    const bool nurbs_ok = degree >= 1 && degree <= 11 && n > degree && int(knots.size()) == n + degree + 1 &&
                          std::is_sorted(knots.begin(), knots.end()) && knots[n] > knots[degree];
    if (!nurbs_ok) {
      // Fall back to the fit points, then the control polygon.
      polyline(xf, fit.size() >= 2 ? fit : ctrl, layer, top);
      return;
    }
    if (int(weights.size()) != n) weights.assign(n, 1.0);
    double len = 0;
    for (int i = 1; i < n; ++i) len += (ctrl[i] - ctrl[i - 1]).norm();
    const int samples = std::clamp(to_int(std::ceil(len / std::max(tol_ * 20, 1e-12)), 0, kBig), std::min(8 * n, 4096), 4096);
    std::vector<Eigen::Vector2d> pts;
    const double u0 = knots[degree], u1 = knots[n];
    std::vector<Eigen::Vector3d> d(degree + 1);
    for (int s = 0; s <= samples; ++s) {
      const double u = u0 + (u1 - u0) * s / samples;
      int k = degree;
      while (k < n - 1 && knots[k + 1] <= u) ++k;
      for (int j = 0; j <= degree; ++j) {
        const int i = k - degree + j;
        d[j] = Eigen::Vector3d(ctrl[i].x() * weights[i], ctrl[i].y() * weights[i], weights[i]);
      }
      for (int r = 1; r <= degree; ++r)
        for (int j = degree; j >= r; --j) {
          const int i = k - degree + j;
          const double den = knots[i + degree - r + 1] - knots[i];
          const double a = den > 0 ? (u - knots[i]) / den : 0.0;
          d[j] = (1 - a) * d[j - 1] + a * d[j];
        }
      if (!(std::abs(d[degree].z()) > 1e-300)) continue;
      pts.push_back(d[degree].head<2>() / d[degree].z());
    }
    polyline(xf, pts, layer, top);
  }

  void expand_insert(const Entity& e, const Xf& xf, const std::string& layer, int depth, const Entity& top) {
    const std::string name = upper(str(e, 2, ""));
    auto it = blocks_.find(name);
    if (it == blocks_.end()) {
      if (!o_.quiet && missing_blocks_.insert(name).second)
        std::cerr << where(e) << ": block '" << text_(name) << "' is not defined (ignored)\n";
      return;
    }
    if (depth >= 16) fail(where(top) + ": INSERT nesting deeper than 16 (recursive block '" + name + "'?)");
    ++inserts_;
    const Block& b = it->second;
    const double sx = num(e, 41, 1), sy = num(e, 42, 1);
    const double rot = num(e, 50, 0) * M_PI / 180;
    const int cols = to_int(num(e, 70, 1), 1, 1000), rows = to_int(num(e, 71, 1), 1, 1000);
    const double cs = num(e, 44, 0), rs = num(e, 45, 0);
    const Eigen::Vector2d ins(num(e, 10, 0), num(e, 20, 0));
    const Xf o = ocs(extrusion(e));
    Xf R;
    R.A << std::cos(rot), -std::sin(rot), std::sin(rot), std::cos(rot);
    Xf S;
    S.A << sx, 0, 0, sy;
    Xf base;
    base.t = -b.base;
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) {
        Xf T;
        T.t = ins + R.A * Eigen::Vector2d(c * cs, r * rs);
        const Xf child = xf * o * T * R * S * base;
        for (const auto& ce : b.entities) emit_entity(ce, child, layer, depth + 1, top);
      }
  }

  // ---- robust extents --------------------------------------------------------------------------
  void drop_outliers() {
    const size_t n = plan_.elements.size();
    if (!o_.drop_outliers || n < 20) return;
    std::vector<double> xs(n), ys(n);
    std::vector<Box2> boxes(n);
    for (size_t i = 0; i < n; ++i) {
      boxes[i] = bounds(plan_.elements[i]);
      const Eigen::Vector2d c = (boxes[i].min + boxes[i].max) / 2;
      xs[i] = c.x();
      ys[i] = c.y();
    }
    auto median = [](std::vector<double> v) {
      std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
      return v[v.size() / 2];
    };
    const double mx = median(xs), my = median(ys);
    std::vector<double> dx(n), dy(n);
    for (size_t i = 0; i < n; ++i) {
      dx[i] = std::abs(xs[i] - mx);
      dy[i] = std::abs(ys[i] - my);
    }
    const double spread = 1.4826 * std::max(median(dx), median(dy));
    if (!(spread > 0)) return;
    const double T = o_.outlier_factor * spread;
    FloorPlan kept;
    kept.source = plan_.source;
    kept.layers = plan_.layers;
    std::vector<std::string> notes;
    for (size_t i = 0; i < n; ++i) {
      const Box2& b = boxes[i];
      const bool inside = b.min.x() >= mx - T && b.max.x() <= mx + T && b.min.y() >= my - T && b.max.y() <= my + T;
      if (inside) {
        kept.elements.push_back(plan_.elements[i]);
      } else {
        ++dropped_;
        if (notes.size() < 8) {
          const Eigen::Vector2d c = (b.min + b.max) / 2 * unit_;
          // %.1f of a coordinate such as 5e300 prints 300 digits: large ones with %g's 6 significant digits.
          auto coord = [](double v) {
            char b[64];
            std::snprintf(b, sizeof b, std::abs(v) < 1e7 ? "%.1f" : "%.6g", v);
            return std::string(b);
          };
          notes.push_back(prov_[i].type + " at line " + std::to_string(prov_[i].line) + " on layer '" +
                          plan_.layers[plan_.elements[i].layer] + "' near (" + coord(c.x()) + ", " + coord(c.y()) + ") m");
        }
      }
    }
    if (dropped_ == 0) return;
    if (kept.elements.empty()) return;  // everything "far": keep the plan as it is
    if (!o_.quiet) {
      std::cerr << source_ << ": dropped " << dropped_ << " element(s) far from the plan (kept the box "
                << (mx - T) * unit_ << ".." << (mx + T) * unit_ << " x " << (my - T) * unit_ << ".." << (my + T) * unit_
                << " m around the median):\n";
      for (const auto& s : notes) std::cerr << "  " << s << "\n";
      if (dropped_ > int(notes.size())) std::cerr << "  ... and " << dropped_ - int(notes.size()) << " more\n";
    }
    plan_ = std::move(kept);
  }

  static constexpr size_t kMaxElements = 2'000'000;
  static constexpr long kMaxVisits = 5'000'000;
  long visits_ = 0;
  std::string source_;
  const PlanLoadOptions& o_;
  int insunits_ = -1;
  std::string codepage_, acadver_;  // $DWGCODEPAGE, $ACADVER
  TextDecoder text_;
  double unit_ = 1, tol_ = 0.01;
  std::vector<Entity> entities_;
  std::unordered_map<std::string, Block> blocks_;
  FloorPlan plan_;
  std::vector<Provenance> prov_;
  std::map<std::string, int> unsupported_;
  std::map<std::string, int> layers_seen_;
  std::set<std::string> missing_blocks_;
  int inserts_ = 0, dropped_ = 0;
};

}  // namespace

FloorPlan read_plan_dxf(const std::string& text, const std::string& source, const PlanLoadOptions& options) {
  return read_plan_dxf(text, source, options, nullptr);
}

FloorPlan read_plan_dxf(const std::string& text, const std::string& source, const PlanLoadOptions& options,
                        DxfStats* stats) {
  DxfLoader loader(source, options);
  return loader.load(text, stats);
}

}  // namespace fploc
