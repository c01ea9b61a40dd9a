#include "fploc/carmen/coverage.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

namespace fploc::carmen {

namespace {

// The returns of a scan at its reference pose, in world coordinates.
template <class F>
void for_each_return(const LaserRecord& s, const CoverageConfig& cfg, F&& f) {
  const double inc = beam_increment(s.ranges.size());
  for (size_t i = 0; i < s.ranges.size(); ++i) {
    const double r = s.ranges[i];
    if (!std::isfinite(r) || r >= cfg.no_return || r < cfg.min_range_m || r > cfg.max_range_m) continue;
    const double a = s.pose.theta - M_PI / 2 + double(i) * inc;
    f(s.pose.x + r * std::cos(a), s.pose.y + r * std::sin(a));
  }
}

// Offsets of the cells whose centres lie within radius of a cell's centre.
std::vector<std::pair<int, int>> disc(double radius_cells) {
  std::vector<std::pair<int, int>> out;
  const int n = int(std::floor(radius_cells + 1e-9));
  for (int dj = -n; dj <= n; ++dj)
    for (int di = -n; di <= n; ++di)
      if (double(di) * di + double(dj) * dj <= radius_cells * radius_cells + 1e-9) out.emplace_back(di, dj);
  return out;
}

}  // namespace

std::vector<size_t> prefix_coverage(const std::vector<LaserRecord>& scans, const CoverageConfig& cfg) {
  const size_t N = scans.size();
  if (!(cfg.resolution > 0) || !(cfg.radius_m >= 0)) throw std::invalid_argument("prefix_coverage: bad resolution/radius");
  std::vector<size_t> out(N, N + 1);
  if (N == 0) return out;
  // Extent of all returns.
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (const auto& s : scans)
    for_each_return(s, cfg, [&](double x, double y) {
      x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
    });
  if (x0 > x1) return out;
  const double m = cfg.radius_m + 2 * cfg.resolution;
  x0 -= m, y0 -= m, x1 += m, y1 += m;
  const int W = int(std::ceil((x1 - x0) / cfg.resolution)) + 1, H = int(std::ceil((y1 - y0) / cfg.resolution)) + 1;
  if (double(W) * H > 4e8) throw std::runtime_error("prefix_coverage: extent too large");
  constexpr uint32_t kNone = UINT32_MAX;
  std::vector<uint32_t> first(size_t(W) * H, kNone);  // first scan with a return within radius of the cell
  const auto nb = disc(cfg.radius_m / cfg.resolution);
  std::vector<uint32_t> e;
  std::vector<std::pair<int, int>> cells;
  for (size_t k = 0; k < N; ++k) {
    e.clear();
    cells.clear();
    for_each_return(scans[k], cfg, [&](double x, double y) {
      const int i = int(std::floor((x - x0) / cfg.resolution)), j = int(std::floor((y - y0) / cfg.resolution));
      cells.emplace_back(i, j);
      e.push_back(first[size_t(j) * W + i]);
    });
    if (!e.empty()) {
      const size_t need = size_t(std::ceil(cfg.covered_ratio * double(e.size())));
      if (need == 0) {
        out[k] = 0;
      } else {
        std::nth_element(e.begin(), e.begin() + long(need - 1), e.end());
        const uint32_t q = e[need - 1];
        out[k] = q == kNone ? k + 1 : std::min<size_t>(size_t(q) + 1, k + 1);
        // Scan k covers itself only if its own returns do (a scan of 3 returns is no map); k + 1 is the
        // natural bound for a scan that is seen by prefix [0, k + 1), which includes it.
      }
    }
    for (const auto& [i, j] : cells) {
      if (first[size_t(j) * W + i] != kNone) continue;  // stamped already (by an earlier scan: its disc is stamped)
      for (const auto& [di, dj] : nb) {
        uint32_t& c = first[size_t(j + dj) * W + (i + di)];
        if (c == kNone) c = uint32_t(k);
      }
    }
  }
  return out;
}

Split choose_split(const std::vector<size_t>& first_cover, const SplitRule& rule) {
  const size_t N = first_cover.size();
  if (N < 2 || !(rule.step > 0) || rule.min_fraction > rule.max_fraction)
    throw std::invalid_argument("choose_split: need >= 2 scans and min_fraction <= max_fraction, step > 0");
  Split best;
  best.covered_share = -1;
  const int n = int(std::floor((rule.max_fraction - rule.min_fraction) / rule.step + 1e-9));
  for (int c = 0; c <= n; ++c) {
    const double f = rule.min_fraction + c * rule.step;
    const size_t S = std::clamp<size_t>(size_t(std::llround(f * double(N))), 1, N - 1);
    size_t cov = 0;
    for (size_t k = S; k < N; ++k) cov += first_cover[k] <= S;
    const double share = double(cov) / double(N - S);
    if (share >= rule.covered_share) return {S, f, share, true};
    if (share > best.covered_share) best = {S, f, share, false};
  }
  return best;
}

std::vector<double> grid_coverage(const Grid& g, const std::vector<LaserRecord>& scans, size_t b, size_t e,
                                  const CoverageConfig& cfg) {
  std::vector<double> out;
  if (g.width <= 0 || g.height <= 0) return std::vector<double>(e > b ? e - b : 0, 0.0);
  // Cells within radius of an occupied cell.
  std::vector<uint8_t> near(g.cells.size(), 0);
  const auto nb = disc(cfg.radius_m / g.resolution);
  for (int j = 0; j < g.height; ++j)
    for (int i = 0; i < g.width; ++i) {
      if (g.cells[size_t(j) * g.width + i] != 100) continue;
      for (const auto& [di, dj] : nb) {
        const int a = i + di, c = j + dj;
        if (a >= 0 && c >= 0 && a < g.width && c < g.height) near[size_t(c) * g.width + a] = 1;
      }
    }
  for (size_t k = b; k < e && k < scans.size(); ++k) {
    size_t n = 0, in = 0;
    for_each_return(scans[k], cfg, [&](double x, double y) {
      ++n;
      const int i = int(std::floor((x - g.origin_x) / g.resolution)), j = int(std::floor((y - g.origin_y) / g.resolution));
      if (i >= 0 && j >= 0 && i < g.width && j < g.height) in += near[size_t(j) * g.width + i];
    });
    out.push_back(n ? double(in) / double(n) : 0.0);
  }
  return out;
}

}  // namespace fploc::carmen
