// ANNF look-ups: the flattened index built from the tree (prepare), single and batch queries,
// leaf boxes and statistics. Construction: build.cpp; file format: format.cpp.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "fploc/annf/annf.h"

namespace fploc::annf {
namespace {

[[noreturn]] void fail(const std::string& m) { throw std::runtime_error(m); }

}  // namespace

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

}  // namespace fploc::annf