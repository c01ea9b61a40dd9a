#include "fploc/annf/annf.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <tuple>
#include <unordered_map>

#include "fploc/floorplan/io.h"

namespace fploc {
namespace {

[[noreturn]] void fail(const std::string& m) { throw std::runtime_error(m); }

// Candidates provably containing the k nearest elements of every point of `box`: elements whose
// minimum distance to the box is <= the k-th smallest maximum distance. `eps` absorbs rounding.
void filter_candidates(const FloorPlan& plan, const std::vector<uint32_t>& in, const Box2& box, int k,
                       std::vector<uint32_t>* out, std::vector<double>* scratch_max, std::vector<double>* scratch_min) {
  out->clear();
  const size_t n = in.size();
  scratch_max->resize(n);
  double m1 = std::numeric_limits<double>::infinity(), m2 = m1;  // the two smallest maxima
  for (size_t i = 0; i < n; ++i) {
    const double m = max_distance(plan.elements[in[i]], box);
    (*scratch_max)[i] = m;
    if (m < m1) {
      m2 = m1;
      m1 = m;
    } else if (m < m2) {
      m2 = m;
    }
  }
  double bound;
  if (n <= size_t(k)) {
    bound = std::numeric_limits<double>::infinity();
  } else if (k <= 2) {
    bound = k == 1 ? m1 : m2;
  } else {
    *scratch_min = *scratch_max;
    std::nth_element(scratch_min->begin(), scratch_min->begin() + (k - 1), scratch_min->end());
    bound = (*scratch_min)[size_t(k - 1)];
  }
  const double eps = 1e-9 * (1.0 + box.size().norm()) + 1e-9;
  for (size_t i = 0; i < n; ++i) {
    // The element's own maximum bounds its minimum: no need to compute the minimum then.
    if ((*scratch_max)[i] <= bound + eps || min_distance(plan.elements[in[i]], box) <= bound + eps) out->push_back(in[i]);
  }
}

struct Pair {
  int first = -1, second = -1;
};

// The two elements nearest to p among `cand` (ties by id).
Pair two_nearest(const FloorPlan& plan, const std::vector<uint32_t>& cand, const Eigen::Vector2d& p,
                 bool distinct = false) {
  Pair out;
  double d1 = std::numeric_limits<double>::infinity(), d2 = d1;
  for (uint32_t id : cand) {
    const double d = distance(plan.elements[id], p);
    if (distinct && d == d1) {  // keep the lower id as first, never a tie as second
      if (int(id) < out.first) out.first = int(id);
      continue;
    }
    if (d < d1 || (d == d1 && int(id) < out.first)) {
      d2 = d1;
      out.second = out.first;
      d1 = d;
      out.first = int(id);
    } else if (d < d2 || (d == d2 && int(id) < out.second)) {
      d2 = d;
      out.second = int(id);
    }
  }
  return out;
}

bool same_pair(const Pair& a, const Pair& b, bool ordered) {
  if (ordered) return a.first == b.first && a.second == b.second;
  return (a.first == b.first && a.second == b.second) || (a.first == b.second && a.second == b.first);
}

Box2 child_box(const Box2& b, int q) {
  const Eigen::Vector2d h = b.size() / 2;
  Box2 c;
  c.min = b.min + Eigen::Vector2d((q & 1) * h.x(), (q >> 1) * h.y());
  c.max = c.min + h;
  return c;
}

Eigen::Vector2d centre(const Box2& b) { return (b.min + b.max) / 2; }

struct Builder {
  const FloorPlan& plan;
  const AnnfOptions& o;
  std::vector<uint32_t>& nodes;
  std::vector<uint32_t>& pool;
  std::unordered_map<std::string, uint32_t> dedupe;
  std::vector<double> smax, smin;
  std::vector<uint32_t> passing;
  std::vector<uint8_t> mark;  // exact refinement: element already in the union
  std::vector<std::vector<uint32_t>> refine_buf;  // per remaining level
  static constexpr uint32_t kLeafBit = 0x80000000u;

  uint32_t leaf(const std::vector<uint32_t>& ids) {
    std::string key(reinterpret_cast<const char*>(ids.data()), ids.size() * sizeof(uint32_t));
    auto it = dedupe.find(key);
    if (it != dedupe.end()) return it->second;
    const size_t off = pool.size();
    if (off >= kLeafBit) fail("ANNF too large (leaf pool exceeds 2^31 entries)");
    pool.push_back(uint32_t(ids.size()));
    pool.insert(pool.end(), ids.begin(), ids.end());
    const uint32_t w = kLeafBit | uint32_t(off);
    dedupe.emplace(std::move(key), w);
    return w;
  }
  uint32_t leaf(const Pair& p) {
    std::vector<uint32_t> ids;
    if (p.first >= 0) ids.push_back(uint32_t(p.first));
    if (p.second >= 0) ids.push_back(uint32_t(p.second));
    return leaf(ids);
  }

  uint32_t alloc4() {
    const size_t idx = nodes.size();
    if (idx + 4 >= kLeafBit) fail("ANNF too large (more than 2^31 nodes)");
    nodes.resize(idx + 4, 0);
    return uint32_t(idx);
  }

  // Paper mode: a child's candidate list (its 2-candidates: they contain the two nearest elements of
  // every point of the field, and every element passing through it) and its two elements.
  void child_pair(const std::vector<uint32_t>& K, const Box2& cb, const Pair& parent, std::vector<uint32_t>* Kc,
                  Pair* pc) {
    filter_candidates(plan, K, cb, 2, Kc, &smax, &smin);
    using C = AnnfOptions::Candidates;
    if (o.paper_candidates == C::kAll) {
      *pc = two_nearest(plan, *Kc, centre(cb), o.paper_distinct_distances);
      return;
    }
    passing.clear();
    for (uint32_t id : *Kc)
      if (min_distance(plan.elements[id], cb) <= 0) passing.push_back(id);
    if (!passing.empty())
      *pc = two_nearest(plan, passing, centre(cb), o.paper_distinct_distances);
    else if (o.paper_candidates == C::kPassingInherit)
      *pc = parent;
    else
      *pc = two_nearest(plan, *Kc, centre(cb), o.paper_distinct_distances);
  }

  // Paper mode: `pair` is this field's two nearest elements to its centre, K its candidates.
  uint32_t paper(const Box2& box, int depth, const std::vector<uint32_t>& K, const Pair& pair) {
    if (depth >= o.max_depth) return leaf(pair);
    if (o.paper_rule == PaperRule::kCollapseFirst || o.paper_rule == PaperRule::kCollapsePair)
      return paper_bottom_up(box, depth, K, pair);
    std::vector<uint32_t> Kc[4];
    Pair pc[4];
    bool all_same = true;
    const bool ordered = o.paper_rule == PaperRule::kChildLeafOrdered;
    for (int q = 0; q < 4; ++q) {
      const Box2 cb = child_box(box, q);
      child_pair(K, cb, pair, &Kc[q], &pc[q]);
      all_same = all_same && same_pair(pc[q], pair, ordered);
    }
    if (o.paper_rule != PaperRule::kFull && all_same) return leaf(pair);  // withdraw the division
    const uint32_t base = alloc4();
    for (int q = 0; q < 4; ++q) {
      uint32_t w;
      const bool child_leaf = (o.paper_rule == PaperRule::kChildLeaf || o.paper_rule == PaperRule::kChildLeafOrdered) &&
                              same_pair(pc[q], pair, ordered);
      if (child_leaf)
        w = leaf(pc[q]);
      else
        w = paper(child_box(box, q), depth + 1, Kc[q], pc[q]);
      nodes[base + q] = w;
    }
    return base;
  }

  // Bottom-up: divide to max_depth, then withdraw a division whose four children are leaves sharing
  // this field's nearest element (or ordered pair). Children are built first; a withdrawn division
  // gives its node groups back (they are the last ones allocated).
  uint32_t paper_bottom_up(const Box2& box, int depth, const std::vector<uint32_t>& K, const Pair& pair) {
    if (depth >= o.max_depth) return leaf(pair);
    const size_t mark = nodes.size();
    uint32_t w[4];
    bool collapse = true;
    for (int q = 0; q < 4; ++q) {
      const Box2 cb = child_box(box, q);
      std::vector<uint32_t> Kc;
      Pair pc;
      child_pair(K, cb, pair, &Kc, &pc);
      w[q] = paper_bottom_up(cb, depth + 1, Kc, pc);
      const bool same = o.paper_rule == PaperRule::kCollapseFirst ? pc.first == pair.first : same_pair(pc, pair, true);
      collapse = collapse && (w[q] & kLeafBit) && same;
    }
    if (collapse) {
      nodes.resize(mark);
      return leaf(pair);
    }
    const uint32_t base = alloc4();
    for (int q = 0; q < 4; ++q) nodes[base + q] = w[q];
    return base;
  }

  // Exact mode: union of the simple-bound sets of the sub-boxes of `box` down to `levels` below it.
  void refine(const Box2& box, const std::vector<uint32_t>& K, int levels, std::vector<uint8_t>* mark,
              std::vector<uint32_t>* out) {
    if (refine_buf.size() <= size_t(levels)) refine_buf.resize(size_t(levels) + 1);
    std::vector<uint32_t>& Kc = refine_buf[size_t(levels)];
    filter_candidates(plan, K, box, 1, &Kc, &smax, &smin);
    if (Kc.size() <= 1 || levels == 0) {
      for (uint32_t id : Kc)
        if (!(*mark)[id]) {
          (*mark)[id] = 1;
          out->push_back(id);
        }
      return;
    }
    for (int q = 0; q < 4; ++q) refine(child_box(box, q), Kc, levels - 1, mark, out);
  }

  // Exact mode: K = a candidate set of box (contains the nearest element of each of its points).
  uint32_t exact(const Box2& box, int depth, const std::vector<uint32_t>& K_in) {
    std::vector<uint32_t> K = K_in;
    if (o.exact_refine_levels > 0 && K.size() > 1) {
      std::vector<uint32_t> R;
      for (int q = 0; q < 4; ++q) refine(child_box(box, q), K, o.exact_refine_levels - 1, &mark, &R);
      for (uint32_t id : R) mark[id] = 0;
      std::sort(R.begin(), R.end());
      K.swap(R);
    }
    if (depth >= o.max_depth || int(K.size()) <= o.exact_max_candidates) {
      // Order by distance to the centre: the first candidate is the likely nearest.
      std::vector<std::pair<double, uint32_t>> order;
      const Eigen::Vector2d c = centre(box);
      for (uint32_t id : K) order.push_back({distance(plan.elements[id], c), id});
      std::sort(order.begin(), order.end());
      std::vector<uint32_t> ids;
      for (auto& x : order) ids.push_back(x.second);
      return leaf(ids);
    }
    std::vector<uint32_t> Kc[4];
    for (int q = 0; q < 4; ++q) filter_candidates(plan, K, child_box(box, q), 1, &Kc[q], &smax, &smin);
    const uint32_t base = alloc4();
    for (int q = 0; q < 4; ++q) {
      const uint32_t w = exact(child_box(box, q), depth + 1, Kc[q]);
      nodes[base + q] = w;
    }
    return base;
  }
};

// Elements another element covers: an exact duplicate (the lower id is kept), a segment lying on a
// longer one, an arc on a circle of the same centre and radius. Every point is at least as far from
// a covered element as from the element covering it, so exact mode leaves them out of its candidate
// sets (the distance returned is the same; CAD plans draw many walls twice: SIST-F4 walls +
// columns has 108 duplicates and 11 contained segments among 1732 elements). Containment is checked
// against elements whose bounding box contains the element's, for plans of up to 50 000 elements
// (beyond that, duplicates only).
std::vector<uint8_t> covered_elements(const FloorPlan& plan) {
  const size_t n = plan.elements.size();
  std::vector<uint8_t> covered(n, 0);
  constexpr double kTol = 1e-12;
  auto same = [&](const Element& e, const Element& f) {
    if (e.kind != f.kind) return false;
    if (e.kind == ElementKind::kSegment)
      return (e.a == f.a && e.b == f.b) || (e.a == f.b && e.b == f.a);
    return e.c == f.c && e.r == f.r && e.a0 == f.a0 && e.a1 == f.a1;
  };
  auto inside = [&](const Element& e, const Element& f) {  // e lies on f (e != f)
    if (e.kind == ElementKind::kSegment && f.kind == ElementKind::kSegment)
      return distance(f, e.a) <= kTol && distance(f, e.b) <= kTol;
    if (e.kind == ElementKind::kArc && f.kind == ElementKind::kCircle) return e.c == f.c && e.r == f.r;
    return false;
  };
  std::vector<Box2> bb(n);
  std::vector<uint32_t> order(n);
  for (size_t i = 0; i < n; ++i) {
    bb[i] = bounds(plan.elements[i]);
    order[i] = uint32_t(i);
  }
  std::sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) {
    return bb[x].min.x() < bb[y].min.x() || (bb[x].min.x() == bb[y].min.x() && x < y);
  });
  if (n > 50000) {  // duplicates only: equal elements are adjacent in a sort by geometry
    auto key = [&](uint32_t i) {
      const Element& e = plan.elements[i];
      Eigen::Vector2d a = e.a, b = e.b;
      if (e.kind == ElementKind::kSegment && (b.x() < a.x() || (b.x() == a.x() && b.y() < a.y()))) std::swap(a, b);
      return std::make_tuple(int(e.kind), a.x(), a.y(), b.x(), b.y(), e.c.x(), e.c.y(), e.r, e.a0, e.a1, i);
    };
    std::sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) { return key(x) < key(y); });
    for (size_t k = 1; k < n; ++k)
      if (same(plan.elements[order[k]], plan.elements[order[k - 1]])) covered[order[k]] = 1;
    return covered;
  }
  for (size_t oi = 0; oi < n; ++oi) {
    const uint32_t i = order[oi];
    const Element& e = plan.elements[i];
    // Covering elements f have bb[f].min.x <= bb[i].min.x: the order's prefix up to i (and ties).
    for (size_t oj = 0; oj < n; ++oj) {
      const uint32_t j = order[oj];
      if (bb[j].min.x() > bb[i].min.x() + kTol) break;
      if (j == i) continue;
      const Box2& fb = bb[j];
      if (fb.max.x() < bb[i].max.x() - kTol || fb.min.y() > bb[i].min.y() + kTol || fb.max.y() < bb[i].max.y() - kTol)
        continue;
      const Element& f = plan.elements[j];
      // Equal (or equal within kTol both ways): the lower id covers the higher one.
      const bool e_in_f = same(e, f) || inside(e, f);
      if (!e_in_f) continue;
      const bool f_in_e = same(e, f) || inside(f, e);
      if (!f_in_e || j < i) {
        covered[i] = 1;
        break;
      }
    }
  }
  return covered;
}

uint64_t fnv1a(const void* data, size_t n, uint64_t h = 1469598103934665603ull) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 1099511628211ull;
  }
  return h;
}

template <typename T>
void put(std::ostream& out, const T& v) {
  out.write(reinterpret_cast<const char*>(&v), sizeof(T));
}
template <typename T>
T get(std::istream& in, const std::string& source) {
  T v{};
  in.read(reinterpret_cast<char*>(&v), sizeof(T));
  if (!in) fail(source + ": truncated map file");
  return v;
}

}  // namespace

const char* to_string(AnnfMode m) { return m == AnnfMode::kExact ? "exact" : "paper"; }
const char* to_string(PaperRule r) {
  switch (r) {
    case PaperRule::kChildLeaf: return "child-leaf";
    case PaperRule::kUndoOnly: return "undo-only";
    case PaperRule::kChildLeafOrdered: return "child-leaf-ordered";
    case PaperRule::kFull: return "full";
    case PaperRule::kCollapseFirst: return "collapse-first";
    case PaperRule::kCollapsePair: return "collapse-pair";
  }
  return "?";
}
AnnfMode parse_annf_mode(const std::string& s) {
  if (s == "paper") return AnnfMode::kPaper;
  if (s == "exact") return AnnfMode::kExact;
  fail("unknown ANNF mode '" + s + "' (paper or exact)");
}
PaperRule parse_paper_rule(const std::string& s) {
  for (PaperRule r : {PaperRule::kChildLeaf, PaperRule::kUndoOnly, PaperRule::kChildLeafOrdered, PaperRule::kFull,
                      PaperRule::kCollapseFirst, PaperRule::kCollapsePair})
    if (s == to_string(r)) return r;
  fail("unknown paper stopping rule '" + s +
       "' (child-leaf, undo-only, child-leaf-ordered, full, collapse-first, collapse-pair)");
}

// Re-groups the subtree under `word` (a node with `levels_left` levels below it down to max depth)
// into 16-ary blocks; returns the word to store for it (a leaf word pointing into lpool_, or a
// block offset). remap: pool_ offset -> lpool_ offset (or ~0u when not yet copied).
uint32_t Annf::flatten(uint32_t word, int levels_left, std::vector<uint32_t>* remap) {
  if (word & kLeafBit) {
    const uint32_t off = word & ~kLeafBit;
    uint32_t& at = (*remap)[off];
    if (at == ~0u) {
      const uint32_t n = pool_[off];
      at = uint32_t(lpool_.size());
      bool arc = false;
      for (uint32_t k = 0; k < n; ++k) arc = arc || plan_.elements[pool_[off + 1 + k]].kind == ElementKind::kArc;
      lpool_.push_back(n | (arc ? kArcFlag : 0));
      for (uint32_t k = 0; k < n; ++k) lpool_.push_back(pool_[off + 1 + k]);
      const uint32_t padded = n > 4 ? n : std::max(uint32_t(fast_k_), (n + 1) & ~1u);
      for (uint32_t k = n; k < padded; ++k) lpool_.push_back(pool_[off + 1]);
      if (lpool_.size() >= kLeafBit) fail("ANNF too large (leaf records)");
    }
    return kLeafBit | at;
  }
  if (levels_left == 1) {  // 4-entry block: the children (leaves at max depth)
    uint32_t entry[4];
    for (int q = 0; q < 4; ++q) entry[q] = flatten(nodes_[word + q], 0, remap);
    const uint32_t at = uint32_t(blocks_.size());
    blocks_.insert(blocks_.end(), entry, entry + 4);
    return at;
  }
  uint32_t entry[16];
  for (uint32_t sy = 0; sy < 4; ++sy)
    for (uint32_t sx = 0; sx < 4; ++sx) {
      uint32_t w = nodes_[word + (((sy >> 1) << 1) | (sx >> 1))];
      if (!(w & kLeafBit)) w = nodes_[w + (((sy & 1u) << 1) | (sx & 1u))];
      entry[sy * 4 + sx] = w;
    }
  // Children first (they append to blocks_), then this block at a 64-byte boundary.
  for (uint32_t& w : entry) w = flatten(w, levels_left - 2, remap);
  while (blocks_.size() % 16) blocks_.push_back(0);
  const uint32_t at = uint32_t(blocks_.size());
  if (size_t(at) + 16 >= kLeafBit) fail("ANNF too large (look-up blocks)");
  blocks_.insert(blocks_.end(), entry, entry + 16);
  return at;
}

void Annf::prepare() {
  leaf_ = options_.root_length / double(1u << (max_depth_ - 1));
  inv_leaf_ = 1.0 / leaf_;
  extent_x_ = double(nx_) * double(1u << (max_depth_ - 1));
  extent_y_ = double(ny_) * double(1u << (max_depth_ - 1));
  geom_.assign(plan_.elements.size(), FastPrim{});
  for (size_t i = 0; i < plan_.elements.size(); ++i) {
    const Element& e = plan_.elements[i];
    FastPrim& f = geom_[i];
    if (e.kind == ElementKind::kSegment) {
      const Eigen::Vector2d d = e.b - e.a;
      const double len = d.norm();
      f.ax = e.a.x();
      f.ay = e.a.y();
      f.ux = len > 0 ? d.x() / len : 1.0;
      f.uy = len > 0 ? d.y() / len : 0.0;
      f.len = len;
    } else {  // circle (arcs: the same fields, but their leaves take the general path)
      f.ax = e.c.x();
      f.ay = e.c.y();
      f.ux = 1.0;
      f.r = e.r;
    }
  }
  // Candidates evaluated by the fast path: 2 if leaves with at most 2 candidates cover 95 % of the
  // area (paper mode: all of it), else 4. Longer leaves take the general loop.
  double area_total = 0, area_le2 = 0;
  for_each_leaf([&](const Box2& b, int, const uint32_t*, int n) {
    const double a = b.size().x() * b.size().y();
    area_total += a;
    if (n <= 2) area_le2 += a;
  });
  fast_k_ = area_le2 >= 0.95 * area_total ? 2 : 4;
  // Dense index at the deepest level whose cell count fits the budget.
  int g = 1;
  const double budget = options_.index_cells ? double(options_.index_cells)
                                             : double(options_.mode == AnnfMode::kExact ? 1u << 20 : 1u << 18);
  while (g < max_depth_ && double(nx_) * ny_ * double(1ull << (2 * g)) <= budget) ++g;
  index_shift_ = max_depth_ - g;
  block_steps_ = (index_shift_ + 1) / 2;
  const uint32_t per = 1u << (g - 1);
  const uint32_t cx = nx_ * per, cy = ny_ * per;
  index_tiles_x_ = (cx + 3) / 4;
  const uint32_t tiles_y = (cy + 3) / 4;
  index_.assign(size_t(index_tiles_x_) * tiles_y * 16, 0);
  blocks_.assign(16, 0);  // the dummy block read by leaves reached before the last step
  lpool_.clear();
  std::vector<uint32_t> remap(pool_.size(), ~0u);
  for (uint32_t j = 0; j < cy; ++j)
    for (uint32_t i = 0; i < cx; ++i) {
      uint32_t node = roots_[size_t(j / per) * nx_ + i / per];
      for (int level = g - 1; level > 0 && !(node & kLeafBit); --level)
        node = nodes_[node + ((((j >> (level - 1)) & 1u)) << 1 | ((i >> (level - 1)) & 1u))];
      // A node at the index depth is reached from exactly one index cell.
      index_[index_slot(i, j)] = flatten(node, max_depth_ - g, &remap);
    }
  blocks_.shrink_to_fit();
  lpool_.shrink_to_fit();
}

Eigen::Vector2d Annf::closest_on(uint32_t id, const Eigen::Vector2d& p) const {
  return closest_point(plan_.elements[id], p).point;
}

int Annf::best_of_leaf_general(const uint32_t* rec, const Eigen::Vector2d& p, double* dist,
                               Eigen::Vector2d* closest) const {
  const int n = int(rec[0] & kCountMask);
  const uint32_t* ids = rec + 1;
  int best = -1;
  double bd = 1e300;
  for (int k = 0; k < n; ++k) {
    const Element& e = plan_.elements[ids[k]];
    double d;
    if (e.kind == ElementKind::kArc) {
      d = distance(e, p);
    } else {
      d = geom_[ids[k]].distance(p);
    }
    if (d < bd) {
      bd = d;
      best = int(ids[k]);
    }
  }
  if (dist) *dist = bd;
  if (closest && best >= 0) *closest = closest_on(uint32_t(best), p);
  return best;
}

Annf Annf::build(const FloorPlan& plan, const AnnfOptions& options) {
  if (plan.elements.empty()) fail(plan.source + ": cannot build an ANNF over an empty plan");
  if (!(options.root_length > 0) || !std::isfinite(options.root_length)) fail("ANNF root length must be > 0");
  if (options.max_depth < 1 || options.max_depth > 20) fail("ANNF max depth must be in 1..20");
  if (options.exact_max_candidates < 1 || options.exact_max_candidates > 0xffff)
    fail("ANNF exact_max_candidates must be in 1..65535");
  if (options.exact_refine_levels < 0 || options.exact_refine_levels > 12)
    fail("ANNF exact_refine_levels must be in 0..12");
  Annf a;
  a.plan_ = plan;
  a.options_ = options;
  a.max_depth_ = options.max_depth;
  const Box2 bb = plan.bounds();
  const double L = options.root_length;
  a.origin_ = bb.min - Eigen::Vector2d(options.margin, options.margin);
  const Eigen::Vector2d size = bb.size() + Eigen::Vector2d(2 * options.margin, 2 * options.margin);
  const double nxd = std::max(1.0, std::ceil(size.x() / L)), nyd = std::max(1.0, std::ceil(size.y() / L));
  // Finest-leaf indices must fit in 31 bits.
  if (nxd * double(1u << (a.max_depth_ - 1)) > 2e9 || nyd * double(1u << (a.max_depth_ - 1)) > 2e9 ||
      nxd * nyd > 5e7)
    fail(plan.source + ": plan too large for root fields of " + std::to_string(L) + " m at depth " +
         std::to_string(a.max_depth_) + " (check the units)");
  a.nx_ = uint32_t(nxd);
  a.ny_ = uint32_t(nyd);
  a.roots_.assign(size_t(a.nx_) * a.ny_, 0);
  Builder b{a.plan_, a.options_, a.nodes_, a.pool_, {}, {}, {}, {}, std::vector<uint8_t>(plan.elements.size(), 0), {}};
  std::vector<uint32_t> all(plan.elements.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = uint32_t(i);
  std::vector<uint32_t> exact_all;  // exact mode: elements that are not covered by another one
  if (options.mode == AnnfMode::kExact) {
    const std::vector<uint8_t> covered = covered_elements(plan);
    for (uint32_t id : all)
      if (!covered[id]) exact_all.push_back(id);
  }
  std::vector<uint32_t> K;
  for (uint32_t j = 0; j < a.ny_; ++j)
    for (uint32_t i = 0; i < a.nx_; ++i) {
      Box2 box;
      box.min = a.origin_ + Eigen::Vector2d(i * L, j * L);
      box.max = box.min + Eigen::Vector2d(L, L);
      uint32_t w;
      if (options.mode == AnnfMode::kPaper) {
        const Pair global = two_nearest(a.plan_, all, centre(box), options.paper_distinct_distances);
        Pair pair;
        b.child_pair(all, box, global, &K, &pair);
        w = b.paper(box, 1, K, pair);
      } else {
        filter_candidates(a.plan_, exact_all, box, 1, &K, &b.smax, &b.smin);
        w = b.exact(box, 1, K);
      }
      a.roots_[size_t(j) * a.nx_ + i] = w;
    }
  a.nodes_.shrink_to_fit();
  a.pool_.shrink_to_fit();
  a.prepare();
  return a;
}

int Annf::nearest_outside(const Eigen::Vector2d& p, double* dist, Eigen::Vector2d* closest) const {
  double d;
  const int id = nearest_element_brute_force(plan_, p, &d);
  if (dist) *dist = d;
  if (closest && id >= 0) *closest = closest_point(plan_.elements[id], p).point;
  return id;
}

// Leaf words of m points (0 = outside), the descent of leaf_word() with the index shift as a
// compile-time constant (no variable shifts; S0 < 0: the run-time shift): first every index read
// (independent loads, many cache misses in flight), then the block steps level by level.
template <int S0>
void Annf::leaf_words(const Eigen::Vector2d* p, size_t m, uint32_t* words) const {  // m <= kChunk
  const double ox = origin_.x(), oy = origin_.y(), inv = inv_leaf_, ex = extent_x_, ey = extent_y_;
  const uint32_t* index = index_.data();
  const uint32_t* blocks = blocks_.data();
  if constexpr (S0 >= 0 && S0 <= 6) {
    // Compile-time shifts; the slot of every block step is computed with the index read, so the
    // block loops only load and select.
    constexpr int kSteps = (S0 + 1) / 2;
    alignas(64) uint8_t slot[kSteps > 0 ? kSteps : 1][kChunk];
    auto cell = [&](size_t k, uint32_t ix, uint32_t iy, bool in) {
      const uint32_t w = index[index_slot(ix >> S0, iy >> S0)];
      words[k] = in ? w : 0u;  // 0: outside (never a valid word: leaf words have kLeafBit)
      int sh = S0;
      for (int st = 0; st < kSteps; ++st) {
        if (sh >= 2) {
          sh -= 2;
          slot[st][k] = uint8_t((((iy >> sh) & 3u) << 2) | ((ix >> sh) & 3u));
        } else {
          sh = 0;
          slot[st][k] = uint8_t(((iy & 1u) << 1) | (ix & 1u));
        }
      }
    };
    size_t k = 0;
    for (; k < m; ++k) {
      const double fx = (p[k].x() - ox) * inv, fy = (p[k].y() - oy) * inv;
      const bool in = fx >= 0 && fy >= 0 && fx < ex && fy < ey;
      cell(k, in ? uint32_t(fx) : 0u, in ? uint32_t(fy) : 0u, in);
    }
    for (int st = 0; st < kSteps; ++st)
      for (size_t k = 0; k < m; ++k) {
        const uint32_t w = words[k], inner = ((w >> 31) - 1u) & (0u - uint32_t(w != 0));
        words[k] = (blocks[(w & inner) + slot[st][k]] & inner) | (w & ~inner);
      }
  } else {
    alignas(64) uint32_t cx[kChunk], cy[kChunk];
    const int s0 = index_shift_, steps = block_steps_;
    for (size_t k = 0; k < m; ++k) {
      const double fx = (p[k].x() - ox) * inv, fy = (p[k].y() - oy) * inv;
      const bool in = fx >= 0 && fy >= 0 && fx < ex && fy < ey;
      const uint32_t ix = in ? uint32_t(fx) : 0u, iy = in ? uint32_t(fy) : 0u;
      cx[k] = ix;
      cy[k] = iy;
      const uint32_t w = index[index_slot(ix >> s0, iy >> s0)];
      words[k] = in ? w : 0u;
    }
    int s = s0;
    for (int st = 0; st < steps; ++st) {
      const int sn = s >= 2 ? s - 2 : 0;
      const uint32_t mask = s >= 2 ? 3u : 1u, up = s >= 2 ? 2u : 1u;
      for (size_t k = 0; k < m; ++k) {
        const uint32_t w = words[k], inner = ((w >> 31) - 1u) & (0u - uint32_t(w != 0));
        const uint32_t sl = (((cy[k] >> sn) & mask) << up) | ((cx[k] >> sn) & mask);
        words[k] = (blocks[(w & inner) + sl] & inner) | (w & ~inner);
      }
      s = sn;
    }
  }
}

template <int S0>
void Annf::batch_impl(const Eigen::Vector2d* pts, size_t n, int* ids, double* dists, Eigen::Vector2d* closest) const {
  // Loop fission in chunks: first the leaf words of a chunk of points (the descent: index and
  // block reads), then their distances (leaf records and geometry). Each loop body is a short
  // dependency chain, so the out-of-order core keeps many points in flight.
  constexpr size_t C = kChunk;
  alignas(64) uint32_t words[C];
  for (size_t base = 0; base < n; base += C) {
    const size_t m = std::min(C, n - base);
    const Eigen::Vector2d* p = pts + base;
    leaf_words<S0>(p, m, words);
    if (!closest) {
      // The fast path in a loop without calls (so pointers stay in registers); points outside the
      // field and long records afterwards.
      const uint32_t* lp = lpool_.data();
      const FastPrim* geom = geom_.data();
      int* id_out = ids + base;
      double* d_out = dists + base;
      bool others = false;
      size_t k = 0;
#if defined(__SSE2__)
      // Two points per SSE2 operation (lanes = points k, k + 1; the same arithmetic per lane as
      // best_of_record(), so the results are bit-identical): half the instructions per point.
      auto dist2 = [&](__m128d px, __m128d py, uint32_t e0, uint32_t e1) { return distance2(geom, e0, e1, px, py); };
      for (; k + 1 < m; k += 2) {
        const uint32_t* r0 = lp + (words[k] & ~kLeafBit);
        const uint32_t* r1 = lp + (words[k + 1] & ~kLeafBit);
        if (__builtin_expect(words[k] == 0 || words[k + 1] == 0 || r0[0] > 4u || r1[0] > 4u, 0)) {
          for (size_t j = k; j < k + 2; ++j) {  // one at a time
            const uint32_t* rec = lp + (words[j] & ~kLeafBit);
            if (words[j] == 0 || rec[0] > 4u) {
              others = true;
              continue;
            }
            double d;
            id_out[j] = int(best_of_record(rec, geom, p[j], &d));
            d_out[j] = d;
          }
          continue;
        }
        const __m128d p0 = _mm_loadu_pd(p[k].data()), p1 = _mm_loadu_pd(p[k + 1].data());
        const __m128d px = _mm_unpacklo_pd(p0, p1), py = _mm_unpackhi_pd(p0, p1);
        uint32_t b0 = r0[1], b1 = r1[1];
        __m128d bd = dist2(px, py, b0, b1);
        {
          const uint32_t c0 = r0[2], c1 = r1[2];
          const __m128d d = dist2(px, py, c0, c1);
          const int mk = _mm_movemask_pd(_mm_cmplt_pd(d, bd));
          bd = _mm_min_pd(d, bd);  // d < bd ? d : bd, per lane
          b0 = (mk & 1) ? c0 : b0;
          b1 = (mk & 2) ? c1 : b1;
        }
        if (r0[0] > 2 || r1[0] > 2) {  // 3-4 candidates in either (padding: the first candidate)
          for (int q = 3; q <= 4; ++q) {
            const uint32_t c0 = r0[0] > 2 ? r0[q] : r0[1], c1 = r1[0] > 2 ? r1[q] : r1[1];
            const __m128d d = dist2(px, py, c0, c1);
            const int mk = _mm_movemask_pd(_mm_cmplt_pd(d, bd));
            bd = _mm_min_pd(d, bd);
            b0 = (mk & 1) ? c0 : b0;
            b1 = (mk & 2) ? c1 : b1;
          }
        }
        id_out[k] = int(b0);
        id_out[k + 1] = int(b1);
        _mm_storeu_pd(d_out + k, bd);
      }
#endif
      for (; k < m; ++k) {
        const uint32_t* rec = lp + (words[k] & ~kLeafBit);
        if (__builtin_expect(words[k] == 0 || rec[0] > 4u, 0)) {
          others = true;
          continue;
        }
        double d;
        id_out[k] = int(best_of_record(rec, geom, p[k], &d));
        d_out[k] = d;
      }
      if (others)
        for (size_t k = 0; k < m; ++k) {
          const uint32_t* rec = lp + (words[k] & ~kLeafBit);
          if (words[k] != 0 && rec[0] <= 4u) continue;
          double d;
          id_out[k] = words[k] ? best_of_leaf_general(rec, p[k], &d, nullptr) : nearest_outside(p[k], &d, nullptr);
          d_out[k] = d;
        }
    } else {
      for (size_t k = 0; k < m; ++k) {
        double d;
        Eigen::Vector2d c;
        ids[base + k] = words[k] ? best_of_leaf(words[k], p[k], &d, &c) : nearest_outside(p[k], &d, &c);
        dists[base + k] = d;
        closest[base + k] = c;
      }
    }
  }
}

void Annf::lookup_batch(const Eigen::Vector2d* pts, size_t n, const uint32_t** ids, int* counts) const {
  constexpr size_t C = kChunk;
  alignas(64) uint32_t words[C];
  for (size_t base = 0; base < n; base += C) {
    const size_t m = std::min(C, n - base);
    switch (index_shift_) {
      case 0: leaf_words<0>(pts + base, m, words); break;
      case 1: leaf_words<1>(pts + base, m, words); break;
      case 2: leaf_words<2>(pts + base, m, words); break;
      case 3: leaf_words<3>(pts + base, m, words); break;
      case 4: leaf_words<4>(pts + base, m, words); break;
      default: leaf_words<-1>(pts + base, m, words); break;
    }
    for (size_t k = 0; k < m; ++k) {
      const uint32_t* rec = lpool_.data() + (words[k] & ~kLeafBit);
      ids[base + k] = words[k] ? rec + 1 : nullptr;
      counts[base + k] = words[k] ? int(rec[0] & kCountMask) : 0;
    }
  }
}

void Annf::nearest_batch(const Eigen::Vector2d* pts, size_t n, int* ids, double* dists,
                         Eigen::Vector2d* closest) const {
  switch (index_shift_) {
    case 0: return batch_impl<0>(pts, n, ids, dists, closest);
    case 1: return batch_impl<1>(pts, n, ids, dists, closest);
    case 2: return batch_impl<2>(pts, n, ids, dists, closest);
    case 3: return batch_impl<3>(pts, n, ids, dists, closest);
    case 4: return batch_impl<4>(pts, n, ids, dists, closest);
    case 5: return batch_impl<5>(pts, n, ids, dists, closest);
    case 6: return batch_impl<6>(pts, n, ids, dists, closest);
    default: return batch_impl<-1>(pts, n, ids, dists, closest);
  }
}

bool Annf::leaf_box(const Eigen::Vector2d& p, Box2* box, int* depth) const {
  const double fx = (p.x() - origin_.x()) * inv_leaf_, fy = (p.y() - origin_.y()) * inv_leaf_;
  if (!(fx >= 0 && fy >= 0 && fx < extent_x_ && fy < extent_y_)) return false;
  const uint32_t ix = uint32_t(fx), iy = uint32_t(fy);
  const int shift = max_depth_ - 1;
  uint32_t node = roots_[(iy >> shift) * nx_ + (ix >> shift)];
  int s = shift, d = 1;
  while (!(node & kLeafBit)) {
    --s;
    ++d;
    node = nodes_[node + (((iy >> s) & 1u) << 1 | ((ix >> s) & 1u))];
  }
  const double len = leaf_ * double(1u << s);
  box->min = origin_ + Eigen::Vector2d(double(ix >> s) * len, double(iy >> s) * len);
  box->max = box->min + Eigen::Vector2d(len, len);
  if (depth) *depth = d;
  return true;
}

Box2 Annf::covered() const {
  Box2 b;
  b.min = origin_;
  b.max = origin_ + Eigen::Vector2d(nx_, ny_) * options_.root_length;
  return b;
}

AnnfStats Annf::stats() const {
  AnnfStats s;
  s.nodes = roots_.size() + nodes_.size();
  s.pool_ids = pool_.size();
  s.bytes = (index_.size() + blocks_.size() + lpool_.size()) * sizeof(uint32_t) + geom_.size() * sizeof(FastPrim);
  s.file_bytes = (roots_.size() + nodes_.size() + pool_.size()) * sizeof(uint32_t);
  size_t total = 0;
  for_each_leaf([&](const Box2&, int depth, const uint32_t*, int n) {
    ++s.leaves;
    total += size_t(n);
    s.max_leaf_candidates = std::max(s.max_leaf_candidates, n);
    s.deepest = std::max(s.deepest, depth);
  });
  s.mean_leaf_candidates = s.leaves ? double(total) / double(s.leaves) : 0;
  return s;
}

void Annf::write(std::ostream& out) const {
  put<uint8_t>(out, uint8_t(options_.mode));
  put<uint8_t>(out, uint8_t(uint8_t(options_.paper_rule) | (options_.paper_distinct_distances ? 0x80 : 0) |
                            (uint8_t(options_.paper_candidates) << 5)));
  put<double>(out, options_.root_length);
  put<int32_t>(out, options_.max_depth);
  // Low 16 bits: exact_max_candidates; high 16: exact_refine_levels (0 in maps written before it).
  put<int32_t>(out, int32_t(uint32_t(options_.exact_max_candidates) | uint32_t(options_.exact_refine_levels) << 16));
  put<double>(out, options_.margin);
  put<double>(out, origin_.x());
  put<double>(out, origin_.y());
  put<uint32_t>(out, nx_);
  put<uint32_t>(out, ny_);
  uint64_t h = 1469598103934665603ull;
  for (const auto* v : {&roots_, &nodes_, &pool_}) {
    put<uint64_t>(out, uint64_t(v->size()));
    out.write(reinterpret_cast<const char*>(v->data()), std::streamsize(v->size() * sizeof(uint32_t)));
    h = fnv1a(v->data(), v->size() * sizeof(uint32_t), h);
  }
  put<uint64_t>(out, h);
}

Annf Annf::read(std::istream& in, FloorPlan plan, const std::string& source) {
  Annf a;
  a.plan_ = std::move(plan);
  const uint8_t mode = get<uint8_t>(in, source), rule_byte = get<uint8_t>(in, source);
  const uint8_t rule = rule_byte & 0x1f, cand = (rule_byte >> 5) & 3;
  if (cand > 2) fail(source + ": corrupt map file (candidates)");
  a.options_.paper_candidates = AnnfOptions::Candidates(cand);
  if (mode > 1 || rule > 5) fail(source + ": corrupt map file (mode/rule)");
  a.options_.paper_distinct_distances = (rule_byte & 0x80) != 0;
  a.options_.mode = AnnfMode(mode);
  a.options_.paper_rule = PaperRule(rule);
  a.options_.root_length = get<double>(in, source);
  a.options_.max_depth = get<int32_t>(in, source);
  const uint32_t mc = uint32_t(get<int32_t>(in, source));
  a.options_.exact_max_candidates = int(mc & 0xffff);
  a.options_.exact_refine_levels = int(mc >> 16);
  a.options_.margin = get<double>(in, source);
  a.origin_.x() = get<double>(in, source);
  a.origin_.y() = get<double>(in, source);
  a.nx_ = get<uint32_t>(in, source);
  a.ny_ = get<uint32_t>(in, source);
  if (!(a.options_.root_length > 0) || !std::isfinite(a.options_.root_length) || a.options_.max_depth < 1 ||
      a.options_.max_depth > 20 || !a.origin_.allFinite() || a.nx_ == 0 || a.ny_ == 0 ||
      double(a.nx_) * double(a.ny_) > 5e7 || double(a.nx_) * double(1u << (a.options_.max_depth - 1)) > 2e9 ||
      double(a.ny_) * double(1u << (a.options_.max_depth - 1)) > 2e9)
    fail(source + ": corrupt map file (header values)");
  a.max_depth_ = a.options_.max_depth;
  uint64_t h = 1469598103934665603ull;
  for (auto* v : {&a.roots_, &a.nodes_, &a.pool_}) {
    const uint64_t n = get<uint64_t>(in, source);
    if (n > (1ull << 31)) fail(source + ": corrupt map file (array size)");
    v->resize(n);
    in.read(reinterpret_cast<char*>(v->data()), std::streamsize(n * sizeof(uint32_t)));
    if (!in) fail(source + ": truncated map file");
    h = fnv1a(v->data(), v->size() * sizeof(uint32_t), h);
  }
  if (get<uint64_t>(in, source) != h) fail(source + ": map file checksum mismatch (corrupt file)");
  if (a.roots_.size() != size_t(a.nx_) * a.ny_ || a.nodes_.size() % 4 != 0)
    fail(source + ": corrupt map file (tree sizes)");
  // Validate every word reachable from the roots, with a depth limit (no cycles, no bad index).
  const size_t ne = a.plan_.elements.size();
  auto check_leaf = [&](uint32_t w) {
    const uint32_t off = w & ~kLeafBit;
    if (off >= a.pool_.size() || size_t(off) + 1 + a.pool_[off] > a.pool_.size() || a.pool_[off] == 0)
      fail(source + ": corrupt map file (leaf)");
    for (uint32_t k = 0; k < a.pool_[off]; ++k)
      if (a.pool_[off + 1 + k] >= ne) fail(source + ": corrupt map file (element id)");
  };
  std::vector<std::pair<uint32_t, int>> stack;
  for (uint32_t w : a.roots_) {
    stack.push_back({w, 1});
    while (!stack.empty()) {
      auto [x, d] = stack.back();
      stack.pop_back();
      if (x & kLeafBit) {
        check_leaf(x);
        continue;
      }
      if (d >= a.max_depth_ || size_t(x) + 4 > a.nodes_.size() || x % 4 != 0)
        fail(source + ": corrupt map file (node)");
      for (int q = 0; q < 4; ++q) stack.push_back({a.nodes_[x + q], d + 1});
    }
  }
  a.prepare();
  return a;
}

void Annf::save(const std::string& path) const {
  std::ofstream f(path, std::ios::binary);
  if (!f) fail(path + ": cannot write (" + std::strerror(errno) + ")");
  f.write(kFpmapMagic, 8);
  put<uint32_t>(f, kFpmapVersion);
  write_plan_binary(plan_, f);
  write(f);
  f.flush();
  if (!f) fail(path + ": write error");
}

Annf Annf::load(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) fail(path + ": cannot open (" + std::strerror(errno) + ")");
  read_fpmap_header(f, path);
  FloorPlan plan = read_plan_binary(f, path);
  plan.source = path;
  Annf a = read(f, std::move(plan), path);
  f.peek();
  if (!f.eof()) fail(path + ": trailing data after the map (corrupt file)");
  return a;
}

}  // namespace fploc
