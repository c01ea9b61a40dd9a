// ANNF construction (Annf::build): the paper-mode quadtree with its stopping rules and the
// exact-mode provable candidate sets. Query: query.cpp; file format: format.cpp.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <tuple>
#include <unordered_map>

#include "fploc/annf/ablation.h"
#include "fploc/annf/annf.h"

namespace fploc::annf {
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
  // A plan in the wrong units (a drawing in mm read as metres: the Barcelona pavilion 52 km wide) gave 33 million root
  // fields and a build that ran for many minutes without a word; a million fields of 6 m cover a 6 x 6 km floor.
  if (nxd * nyd > kMaxRootFields) {
    char what[200];
    std::snprintf(what, sizeof what, "plan of %.0f x %.0f m is too large for a floor plan (%.0f root fields of %g m, at most %.0f)",
                  bb.size().x(), bb.size().y(), nxd * nyd, L, kMaxRootFields);
    fail(plan.source + ": " + what +
         "; check the units (a drawing in mm or cm read as metres: --units mm, or in a graph plan { units: \"mm\" })");
  }
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

}  // namespace fploc::annf