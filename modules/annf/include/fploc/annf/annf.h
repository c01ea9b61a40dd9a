// Approximate / exact nearest-neighbour field (ANNF) over a floor plan (paper section III-B).
//
// The plan's bounding box is covered by square root fields of `root_length` metres (origin at the
// box minimum). Each root field is a quadtree; depth 1 is the root field itself, so the finest leaf
// is root_length / 2^(max_depth-1) (6 m, depth 7 -> 9.375 cm, the paper's Table III).
//
// Modes
//  - kPaper: each field stores the two elements nearest to its centre; subdivision stops by the
//    paper's rules (see PaperRule). A look-up returns those two; `nearest()` returns the closer one
//    to the query point. Approximate.
//  - kExact: each leaf stores the candidate set that provably contains the nearest element of every
//    point in the leaf (elements whose minimum distance to the leaf box is <= the smallest maximum
//    distance of any element to the box), subdividing while the set has more than
//    `exact_max_candidates` elements (and depth < max_depth). `nearest()` is exact inside the
//    covered area and O(depth + candidates). Points outside the covered area fall back to brute
//    force in `nearest()` (still exact) and return nullptr from `lookup()`.
//
// Inner-loop API (allocation-free, thread-safe for concurrent readers):
//   int n; const uint32_t* ids = annf.lookup(p, &n);   // candidate element ids of p's leaf
//   double d; Eigen::Vector2d q; int id = annf.nearest(p, &d, &q);  // best element, distance, point
//
// Save/load: `.fpmap` = "FPLOCMAP" + u32 version + plan block (fploc/floorplan/io.h) + tree block.
// load() checks magic, version, sizes and every index and throws std::runtime_error("FILE: ...")
// on a bad, truncated or old file.
#pragma once
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iosfwd>
#include <new>
#include <string>
#include <vector>

#include "fploc/floorplan/plan.h"

namespace fploc {

enum class AnnfMode : uint8_t { kPaper = 0, kExact = 1 };

// Readings of the paper's stopping rules ("If a child subfield shares the same two nearest elements
// with its parent field, it will not be further divided and set as a leaf field. If all four
// subfields ... have the same two nearest neighbours as their parent's, the division operation will
// be withdrawn").
enum class PaperRule : uint8_t {
  kChildLeaf = 0,      // A child equal to its parent becomes a leaf; all four equal -> undo split.
  kUndoOnly = 1,       // Only "all four equal -> undo"; children equal to the parent still divide.
  kChildLeafOrdered = 2,  // As kChildLeaf, "same" compares the ordered pair (1st, 2nd).
  kFull = 3,           // No stopping rule: every field divides to max_depth (upper bound on accuracy).
  // Bottom-up readings: every field is divided to max_depth first; a division is then withdrawn
  // (recursively, from the deepest level up) when all four children are leaves that share the
  // parent's nearest element (kCollapseFirst: what the authors' public demo does, reverse-engineered
  // from its leaf table, docs/notes/annf.md) or its ordered pair (kCollapsePair).
  kCollapseFirst = 4,
  kCollapsePair = 5,
};

struct AnnfOptions {
  AnnfMode mode = AnnfMode::kPaper;
  double root_length = 6.0;  // metres
  int max_depth = 7;         // 1 = root fields only
  PaperRule paper_rule = PaperRule::kChildLeafOrdered;  // closest to Table III (docs/notes/annf.md)
  int exact_max_candidates = 4;  // exact mode: subdivide while a leaf holds more candidates
  // Metres added around the plan's bounding box: scan points just outside the outer walls stay
  // inside the field (outside it nearest() falls back to brute force).
  double margin = 2.0;
  // Paper mode: "two nearest" keeps two elements at *different* distances from the field centre
  // (an element tied with the first, e.g. the other wall at a shared corner, is skipped), as the
  // authors' public ANNF demo does (its leaf table shows this).
  bool paper_distinct_distances = false;
  // Paper mode, literal reading of "we iterate over every element, check which fields they are
  // passing through, and note down the distance to the center of each field": a field's two
  // elements are chosen only among the elements passing through it. A field no element passes
  // through gets the two nearest of the whole plan (kPassingElseAll) or keeps its parent's two
  // (kPassingInherit; a root field: the two nearest of the whole plan).
  enum class Candidates : uint8_t { kAll = 0, kPassingElseAll = 1, kPassingInherit = 2 };
  Candidates paper_candidates = Candidates::kAll;
  // Speed only (not saved, no effect on results): the top levels of the trees are flattened into a
  // dense index of at most this many cells so a look-up starts near the leaf.
  uint32_t index_cells = 1u << 18;
};

const char* to_string(AnnfMode m);
const char* to_string(PaperRule r);
AnnfMode parse_annf_mode(const std::string& s);    // "paper" | "exact"; throws otherwise
PaperRule parse_paper_rule(const std::string& s);  // "child-leaf" | "undo-only" | "child-leaf-ordered" | "full" |
                                                   // "collapse-first" | "collapse-pair"

struct AnnfStats {
  size_t nodes = 0, leaves = 0, pool_ids = 0;
  size_t bytes = 0;       // memory of the look-up structure (index + nodes + leaf records with geometry)
  size_t file_bytes = 0;  // compact tree as saved (roots + nodes + id pool), without the plan
  int max_leaf_candidates = 0;
  double mean_leaf_candidates = 0;
  int deepest = 0;
};

class Annf {
 public:
  Annf() = default;

  // Builds the field over `plan` (copied in, so the Annf is self-contained). Throws on an empty plan
  // or bad options.
  static Annf build(const FloorPlan& plan, const AnnfOptions& options = {});

  // Candidate ids of the leaf containing p (2 or 1 in paper mode, the provable set in exact mode);
  // nullptr and *count = 0 when p is outside the covered area. Never allocates.
  const uint32_t* lookup(const Eigen::Vector2d& p, int* count) const {
    const double fx = (p.x() - origin_.x()) * inv_leaf_, fy = (p.y() - origin_.y()) * inv_leaf_;
    if (!(fx >= 0 && fy >= 0 && fx < extent_x_ && fy < extent_y_)) {
      *count = 0;
      return nullptr;
    }
    const uint32_t ix = uint32_t(fx), iy = uint32_t(fy);
    // Root field by rounding (through a dense index of the tree's top levels), then descend.
    int s = index_shift_;
    uint32_t node = index_[size_t(iy >> s) * index_nx_ + (ix >> s)];
    while (!(node & kLeafBit)) {
      --s;
      node = fnodes_[node + (((iy >> s) & 1u) << 1 | ((ix >> s) & 1u))];
    }
    const uint32_t* leaf = fast_.data() + (node & ~kLeafBit);
    *count = int(leaf[0]);
    return leaf + 1;
  }

  // Best element among the leaf's candidates (exact in exact mode; the better of the two in paper
  // mode). Outside the covered area: brute force. Returns -1 only for an empty field.
  int nearest(const Eigen::Vector2d& p, double* dist = nullptr, Eigen::Vector2d* closest = nullptr) const {
    int n;
    const uint32_t* ids = lookup(p, &n);
    if (!ids) return nearest_outside(p, dist, closest);
    // The leaf record holds a copy of its candidates' geometry right after the ids (one cache
    // line or two): no further dependent memory access.
    const uint32_t* g = ids - 1 + ((n + 2) & ~1);
    int best = -1;
    double bd2 = 1e300, bx = 0, by = 0;
    for (int k = 0; k < n; ++k, g += 10) {
      FastPrim s;
      std::memcpy(&s, g, sizeof s);
      double qx, qy;
      if (__builtin_expect(s.inv_l2 >= 0, 1)) {
        const double t = std::min(1.0, std::max(0.0, ((p.x() - s.ax) * s.dx + (p.y() - s.ay) * s.dy) * s.inv_l2));
        qx = s.ax + t * s.dx;
        qy = s.ay + t * s.dy;
      } else if (s.inv_l2 == -2) {  // circle: centre (ax, ay), radius dx
        const double vx = p.x() - s.ax, vy = p.y() - s.ay, len = std::sqrt(vx * vx + vy * vy);
        const double k = len > 0 ? s.dx / len : 0.0;
        qx = len > 0 ? s.ax + vx * k : s.ax + s.dx;
        qy = len > 0 ? s.ay + vy * k : s.ay;
      } else {
        const ClosestPoint cp = closest_point(plan_.elements[ids[k]], p);
        qx = cp.point.x();
        qy = cp.point.y();
      }
      const double d2 = (qx - p.x()) * (qx - p.x()) + (qy - p.y()) * (qy - p.y());
      // Branch-free selection (mispredictions would flush the next queries' memory loads).
      const bool better = d2 < bd2;
      bd2 = better ? d2 : bd2;
      best = better ? int(ids[k]) : best;
      bx = better ? qx : bx;
      by = better ? qy : by;
    }
    if (dist) *dist = std::sqrt(bd2);
    if (closest) *closest = Eigen::Vector2d(bx, by);
    return best;
  }

  // Batch form of nearest() for a whole scan: the same results as calling nearest() for each point,
  // but memory accesses of later points are prefetched while earlier ones are computed (a look-up
  // is memory-latency bound on large plans). ids/dists may not alias pts. closest may be nullptr.
  void nearest_batch(const Eigen::Vector2d* pts, size_t n, int* ids, double* dists,
                     Eigen::Vector2d* closest = nullptr) const;

  // Like nearest() but also returns the first candidate (paper mode: the leaf's "1st element").
  int first_candidate(const Eigen::Vector2d& p) const {
    int n;
    const uint32_t* c = lookup(p, &n);
    return n ? int(c[0]) : -1;
  }

  // Leaf box containing p (for rendering/debugging); false outside.
  bool leaf_box(const Eigen::Vector2d& p, Box2* box, int* depth = nullptr) const;
  // Visits every leaf: fn(box, depth, ids, count).
  template <typename F>
  void for_each_leaf(F&& fn) const;

  const FloorPlan& plan() const { return plan_; }
  const AnnfOptions& options() const { return options_; }
  AnnfStats stats() const;
  double leaf_length() const { return leaf_; }
  Box2 covered() const;

  void save(const std::string& path) const;
  static Annf load(const std::string& path);
  void write(std::ostream& out) const;  // tree block only
  static Annf read(std::istream& in, FloorPlan plan, const std::string& source);

 private:
  static constexpr uint32_t kLeafBit = 0x80000000u;
  // Geometry copy in a leaf record (segments: a, b-a, 1/|b-a|^2; circles: inv_l2 = -2, centre in
  // ax, ay, radius in dx; arcs: inv_l2 = -1, evaluated from the plan).
  struct FastPrim {
    double ax, ay, dx, dy, inv_l2;
  };
  static_assert(sizeof(FastPrim) == 40);
  int nearest_outside(const Eigen::Vector2d& p, double* dist, Eigen::Vector2d* closest) const;
  void prepare();

  FloorPlan plan_;
  AnnfOptions options_;
  Eigen::Vector2d origin_{0, 0};
  double leaf_ = 1, inv_leaf_ = 1;
  double extent_x_ = 0, extent_y_ = 0;  // covered area in finest-leaf units
  uint32_t nx_ = 0, ny_ = 0;
  int max_depth_ = 1;
  std::vector<uint32_t> roots_;  // nx*ny, node word: leaf bit | pool offset, or index of 4 children
  std::vector<uint32_t> nodes_;  // groups of 4 child words
  std::vector<uint32_t> pool_;   // [count, ids...] per leaf
  // Derived in prepare() (not saved): dense top-level index, nodes with leaf words pointing into
  // fast_, and fast_ = per leaf [count, ids..., pad, FastPrim x count], each record aligned to 64 B
  // (128 B when longer than 64 B) so the whole record arrives with one memory round trip.
  template <typename T>
  struct Aligned128 {
    using value_type = T;
    Aligned128() = default;
    template <typename U>
    Aligned128(const Aligned128<U>&) {}
    T* allocate(size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t(128))); }
    void deallocate(T* p, size_t) { ::operator delete(p, std::align_val_t(128)); }
    template <typename U>
    bool operator==(const Aligned128<U>&) const { return true; }
    template <typename U>
    bool operator!=(const Aligned128<U>&) const { return false; }
  };
  std::vector<uint32_t> index_;
  std::vector<uint32_t> fnodes_;
  std::vector<uint32_t, Aligned128<uint32_t>> fast_;
  uint32_t index_nx_ = 0;
  int index_shift_ = 0;
};

template <typename F>
void Annf::for_each_leaf(F&& fn) const {
  struct Item {
    uint32_t word;
    Box2 box;
    int depth;
  };
  std::vector<Item> stack;
  const double L = options_.root_length;
  for (uint32_t j = 0; j < ny_; ++j)
    for (uint32_t i = 0; i < nx_; ++i) {
      Box2 b;
      b.min = origin_ + Eigen::Vector2d(i * L, j * L);
      b.max = b.min + Eigen::Vector2d(L, L);
      stack.push_back({roots_[j * nx_ + i], b, 1});
      while (!stack.empty()) {
        Item it = stack.back();
        stack.pop_back();
        if (it.word & kLeafBit) {
          const uint32_t* leaf = pool_.data() + (it.word & ~kLeafBit);
          fn(it.box, it.depth, leaf + 1, int(leaf[0]));
          continue;
        }
        const Eigen::Vector2d h = it.box.size() / 2;
        for (int q = 0; q < 4; ++q) {
          Box2 c;
          c.min = it.box.min + Eigen::Vector2d((q & 1) * h.x(), (q >> 1) * h.y());
          c.max = c.min + h;
          stack.push_back({nodes_[it.word + q], c, it.depth + 1});
        }
      }
    }
}

}  // namespace fploc
