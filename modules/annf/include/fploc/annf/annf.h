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
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <iosfwd>
#include <new>
#include <string>
#include <vector>

#include "fploc/floorplan/plan.h"

namespace fploc::annf {

enum class AnnfMode : uint8_t { kPaper = 0, kExact = 1 };

// Annf::build refuses a plan needing more root fields than this (a 6 x 6 km floor at the default 6 m root): a plan
// that large is a drawing read in the wrong units, and its build ran for many minutes.
inline constexpr double kMaxRootFields = 1e6;

// Readings of the paper's stopping rules and candidate choice: the enumerators (and their names for
// the command line) are in the bench-only header fploc/annf/ablation.h; the localizer uses the
// defaults below. The value 2 is kChildLeafOrdered.
enum class PaperRule : uint8_t;

struct AnnfOptions {
  AnnfMode mode = AnnfMode::kPaper;
  double root_length = 6.0;  // metres
  int max_depth = 7;         // 1 = root fields only
  // The defaults of the three paper-mode readings (rule, distinct distances, candidates) are the
  // combination closest to Table III on the Corridor plan (docs/notes/annf.md: no reading
  // reproduces the table; the best few differ by < 3 points summed over its 12 numbers).
  PaperRule paper_rule = PaperRule{2};  // kChildLeafOrdered (fploc/annf/ablation.h)
  // Exact mode: subdivide while a leaf holds more candidates. 2: most look-ups evaluate one SSE2
  // pair of candidates (docs/notes/annf.md has the measured trade-off against 4).
  int exact_max_candidates = 2;
  // Exact mode: a field's candidate set is the union of the simple bound's sets over its quadrants,
  // recursively, down to this many levels below the field (stopping early where one element is
  // left). Still provable (each sub-box's set contains the nearest element of each of its points),
  // much tighter than the simple bound near walls and corners, so fields stop dividing earlier.
  // 0 = the simple bound only. Saved with the map (it changes the tree, not the look-up).
  int exact_refine_levels = 2;
  // Metres added around the plan's bounding box: scan points just outside the outer walls stay
  // inside the field (outside it nearest() falls back to brute force).
  double margin = 2.0;
  // Paper mode: "two nearest" keeps two elements at *different* distances from the field centre
  // (an element tied with the first, e.g. the other wall at a shared corner, is skipped), as the
  // authors' public ANNF demo does (its leaf table shows this).
  bool paper_distinct_distances = true;
  // Paper mode, literal reading of "we iterate over every element, check which fields they are
  // passing through, and note down the distance to the center of each field": a field's two
  // elements are chosen only among the elements passing through it. A field no element passes
  // through gets the two nearest of the whole plan (kPassingElseAll) or keeps its parent's two
  // (kPassingInherit; a root field: the two nearest of the whole plan).
  enum class Candidates : uint8_t;  // kAll, kPassingElseAll, kPassingInherit: fploc/annf/ablation.h
  Candidates paper_candidates = Candidates{1};  // kPassingElseAll
  // Speed only (not saved, no effect on results): the top levels of the trees are flattened into a
  // dense index of at most this many cells so a look-up starts near the leaf. 0 = 2^18 in paper
  // mode, 2^20 in exact mode (deeper trees; measured fastest on SIST-F4, docs/notes/annf.md).
  uint32_t index_cells = 0;
};

const char* to_string(AnnfMode m);
AnnfMode parse_annf_mode(const std::string& s);    // "paper" | "exact"; throws otherwise

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
    const uint32_t w = leaf_word(p);
    if (!w) {
      *count = 0;
      return nullptr;
    }
    const uint32_t* rec = lpool_.data() + (w & ~kLeafBit);
    *count = int(rec[0] & kCountMask);
    return rec + 1;
  }

  // Best element among the leaf's candidates (exact in exact mode; the better of the two in paper
  // mode). Outside the covered area: brute force. Returns -1 only for an empty field.
  int nearest(const Eigen::Vector2d& p, double* dist = nullptr, Eigen::Vector2d* closest = nullptr) const {
    const uint32_t w = leaf_word(p);
    if (!w) return nearest_outside(p, dist, closest);
    return best_of_leaf(w, p, dist, closest);
  }

  // Batch form of nearest() for a whole scan: the same results as calling nearest() for each point,
  // 1.7-2x faster per point (the look-ups of a chunk of points are done stage by stage, so many
  // are in flight at once). ids/dists may not alias pts. closest may be nullptr.
  void nearest_batch(const Eigen::Vector2d* pts, size_t n, int* ids, double* dists,
                     Eigen::Vector2d* closest = nullptr) const;
  // Batch form of lookup(): ids[i] / counts[i] as lookup(pts[i], &counts[i]) returns them.
  void lookup_batch(const Eigen::Vector2d* pts, size_t n, const uint32_t** ids, int* counts) const;

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
  static constexpr uint32_t kArcFlag = 0x40000000u, kCountMask = 0x3fffffffu;
  // Per-element geometry for the distance, one array indexed by element id (48 B per element: 83 kB
  // for SIST-F4 walls + columns), so it stays in cache while the index is what a look-up fetches
  // from memory. Segments: start a, unit direction u, length len, r = 0. Circles: a = centre,
  // u = (1, 0), len = 0, r = radius. For both, with v = p - a, s = v.u:
  //   distance = | sqrt((v x u)^2 + (s - clamp(s, 0, len))^2) - r |
  // (for a circle: | |v| - r |). Arcs are evaluated from the plan (their leaves are flagged).
  struct alignas(16) FastPrim {
    double ax, ay, ux, uy, len, r;
    double distance(const Eigen::Vector2d& p) const {
      const double vx = p.x() - ax, vy = p.y() - ay;
      const double s = vx * ux + vy * uy, perp = vx * uy - vy * ux;
      const double over = s - std::min(len, std::max(0.0, s));
      return std::abs(std::sqrt(perp * perp + over * over) - r);
    }
  };
  static_assert(sizeof(FastPrim) == 48);
#if defined(__SSE2__)
  // FastPrim::distance of two elements in the two SSE2 lanes (lane k: element ek, point (px[k], py[k]));
  // the same arithmetic per lane as FastPrim::distance, so the results are bit-identical.
  [[gnu::always_inline]] static __m128d distance2(const FastPrim* geom, uint32_t e0, uint32_t e1, __m128d px,
                                                  __m128d py) {
    const __m128d zero = _mm_setzero_pd(), sign = _mm_set1_pd(-0.0);
    const double* g0 = &geom[e0].ax;
    const double* g1 = &geom[e1].ax;
    const __m128d a0 = _mm_load_pd(g0), a1 = _mm_load_pd(g1);
    const __m128d d0 = _mm_load_pd(g0 + 2), d1 = _mm_load_pd(g1 + 2);
    const __m128d r0 = _mm_load_pd(g0 + 4), r1 = _mm_load_pd(g1 + 4);
    const __m128d ax = _mm_unpacklo_pd(a0, a1), ay = _mm_unpackhi_pd(a0, a1);
    const __m128d ux = _mm_unpacklo_pd(d0, d1), uy = _mm_unpackhi_pd(d0, d1);
    const __m128d len = _mm_unpacklo_pd(r0, r1), rad = _mm_unpackhi_pd(r0, r1);
    const __m128d vx = _mm_sub_pd(px, ax), vy = _mm_sub_pd(py, ay);
    const __m128d along = _mm_add_pd(_mm_mul_pd(vx, ux), _mm_mul_pd(vy, uy));
    const __m128d perp = _mm_sub_pd(_mm_mul_pd(vx, uy), _mm_mul_pd(vy, ux));
    const __m128d over = _mm_sub_pd(along, _mm_min_pd(len, _mm_max_pd(along, zero)));
    const __m128d e = _mm_sqrt_pd(_mm_add_pd(_mm_mul_pd(perp, perp), _mm_mul_pd(over, over)));
    return _mm_andnot_pd(sign, _mm_sub_pd(e, rad));
  }
#endif

  // Look-up structure derived from the tree in prepare() (not saved): the tree's top levels as a
  // dense index at depth g (4 x 4 cells per 64-byte line), and below it the tree re-grouped into
  // 16-ary blocks (one 64-byte line = the 4 x 4 descendants two levels down; a 4-entry block when
  // one level is left). Index and block entries are a leaf word (kLeafBit | offset of the leaf's
  // record in lpool_) or the offset of a block in blocks_. The descent always takes block_steps_
  // steps, without branches: a leaf reached early reads the dummy block at offset 0 and keeps its
  // word. Returns 0 outside the covered area.
  [[gnu::always_inline]] uint32_t leaf_word(const Eigen::Vector2d& p) const {
    const double fx = (p.x() - origin_.x()) * inv_leaf_, fy = (p.y() - origin_.y()) * inv_leaf_;
    if (!(fx >= 0 && fy >= 0 && fx < extent_x_ && fy < extent_y_)) return 0;
    const uint32_t ix = uint32_t(fx), iy = uint32_t(fy);
    int s = index_shift_;
    uint32_t w = index_[index_slot(ix >> s, iy >> s)];
    for (int k = 0; k < block_steps_; ++k) {
      const uint32_t inner = (w >> 31) - 1u;  // all ones for a block offset, 0 for a leaf
      uint32_t slot;
      if (s >= 2) {
        s -= 2;
        slot = (((iy >> s) & 3u) << 2) | ((ix >> s) & 3u);
      } else {
        s = 0;
        slot = ((iy & 1u) << 1) | (ix & 1u);
      }
      const uint32_t next = blocks_[(w & inner) + slot];
      w = (next & inner) | (w & ~inner);
    }
    return w;
  }
  size_t index_slot(uint32_t cx, uint32_t cy) const {
    return ((size_t(cy >> 2) * index_tiles_x_ + (cx >> 2)) << 4) | ((cy & 3u) << 2) | (cx & 3u);
  }
  // Leaf record in lpool_: [count | kArcFlag if a candidate is an arc, ids..., padding], the ids
  // padded with copies of the first to at least fast_k_ entries and to an even count, so the fast
  // path evaluates candidates two at a time in SSE2 lanes: the first pair always, the second when
  // there are 3 or 4 (the only data-dependent branch; never taken in paper mode, always when
  // fast_k_ = 4). Longer records and arcs take the general loop. (Copying the geometry
  // into the records saves a dependent access but makes the records 4x larger: measured slower
  // near walls, where the look-up is cache-bound, docs/notes/annf.md.)
  [[gnu::always_inline]] int best_of_leaf(uint32_t w, const Eigen::Vector2d& p, double* dist,
                                          Eigen::Vector2d* closest) const {
    const uint32_t* rec = lpool_.data() + (w & ~kLeafBit);
    if (__builtin_expect(rec[0] > 4u, 0)) return best_of_leaf_general(rec, p, dist, closest);
    double bd;
    const uint32_t best = best_of_record(rec, geom_.data(), p, &bd);
    if (dist) *dist = bd;
    if (closest) *closest = closest_on(best, p);
    return int(best);
  }
  // The fast path on a record of at most 4 candidates.
  // (static, with the geometry pointer passed in, so a caller's loop keeps it in a register)
  [[gnu::always_inline]] static uint32_t best_of_record(const uint32_t* rec, const FastPrim* geom,
                                                        const Eigen::Vector2d& p, double* dist) {
#if !defined(__SSE2__)
    // Portable fallback (non-x86 builds): the same candidates, one at a time.
    const int n = int(rec[0]);
    uint32_t best = rec[1];
    double bd = geom[rec[1]].distance(p);
    for (int k = 1; k < (n > 2 ? 4 : 2); ++k) {
      const double d = geom[rec[1 + k]].distance(p);
      best = d < bd ? rec[1 + k] : best;
      bd = d < bd ? d : bd;
    }
    *dist = bd;
    return best;
#else
    const __m128d pp = _mm_loadu_pd(p.data());
    const __m128d px = _mm_unpacklo_pd(pp, pp), py = _mm_unpackhi_pd(pp, pp);
    // Branch-free selection; the first of equal candidates wins.
    const uint32_t i0 = rec[1], i1 = rec[2];
    const __m128d d01 = distance2(geom, i0, i1, px, py);
    double bd = _mm_cvtsd_f64(d01);
    const double d1 = _mm_cvtsd_f64(_mm_unpackhi_pd(d01, d01));
    uint32_t best = d1 < bd ? i1 : i0;
    bd = d1 < bd ? d1 : bd;
    if (rec[0] > 2) {  // 3 or 4 candidates (always in exact mode with fast_k_ = 4)
      const uint32_t i2 = rec[3], i3 = rec[4];
      const __m128d d23 = distance2(geom, i2, i3, px, py);
      const double d2 = _mm_cvtsd_f64(d23), d3 = _mm_cvtsd_f64(_mm_unpackhi_pd(d23, d23));
      best = d2 < bd ? i2 : best;
      bd = d2 < bd ? d2 : bd;
      best = d3 < bd ? i3 : best;
      bd = d3 < bd ? d3 : bd;
    }
    *dist = bd;
    return best;
#endif
  }
  Eigen::Vector2d closest_on(uint32_t id, const Eigen::Vector2d& p) const;
  int best_of_leaf_general(const uint32_t* rec, const Eigen::Vector2d& p, double* dist, Eigen::Vector2d* closest) const;
  int nearest_outside(const Eigen::Vector2d& p, double* dist, Eigen::Vector2d* closest) const;
  static constexpr size_t kChunk = 256;  // points per stage in the batch look-ups
  template <int S0>
  [[gnu::always_inline]] inline void leaf_words(const Eigen::Vector2d* p, size_t m, uint32_t* words) const;
  template <int S0>
  void batch_impl(const Eigen::Vector2d* pts, size_t n, int* ids, double* dists, Eigen::Vector2d* closest) const;
  void prepare();
  uint32_t flatten(uint32_t word, int levels_left, std::vector<uint32_t>* remap);

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
  template <typename T>
  struct Aligned64 {
    using value_type = T;
    Aligned64() = default;
    template <typename U>
    Aligned64(const Aligned64<U>&) {}
    T* allocate(size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t(64))); }
    void deallocate(T* p, size_t) { ::operator delete(p, std::align_val_t(64)); }
    template <typename U>
    bool operator==(const Aligned64<U>&) const { return true; }
    template <typename U>
    bool operator!=(const Aligned64<U>&) const { return false; }
  };
  std::vector<uint32_t, Aligned64<uint32_t>> index_, blocks_, lpool_;
  std::vector<FastPrim, Aligned64<FastPrim>> geom_;
  uint32_t index_tiles_x_ = 0;
  int index_shift_ = 0;  // finest-leaf index >> index_shift_ = index cell
  int block_steps_ = 0;  // block levels below the index (ceil((max_depth - g) / 2))
  int fast_k_ = 2;       // candidates the fast path always evaluates (2 or 4)
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

}  // namespace fploc::annf