#include "fploc/laser2d/correlative_search.h"

#include <algorithm>
#include <cmath>

namespace fploc::laser2d {

ScorePyramid::ScorePyramid(const DistanceField& df, double score_sigma_m, int levels)
    : w_(df.width()), h_(df.height()) {
  const double k = -0.5 / (score_sigma_m * score_sigma_m);
  s_.resize(df.data().size());
  for (size_t i = 0; i < s_.size(); ++i) s_[i] = float(std::exp(k * double(df.data()[i]) * df.data()[i]));
  auto q = [](float v) { return uint8_t(std::min(255.f, std::ceil(v * 255.f))); };
  const size_t n = size_t(w_) * size_t(h_);
  for (int h = 1; h < levels; ++h) {
    std::vector<uint8_t> out(n);
    const int s = 1 << (h - 1);  // the previous level's block size
    for (int j = 0; j < h_; ++j)
      for (int i = 0; i < w_; ++i) {
        float m = 0;
        int mq = 0;
        for (int b = 0; b < 2; ++b)
          for (int a = 0; a < 2; ++a) {
            const int ii = i + a * s, jj = j + b * s;
            if (ii >= w_ || jj >= h_) continue;
            if (h == 1) m = std::max(m, s_[size_t(jj) * size_t(w_) + size_t(ii)]);
            else mq = std::max<int>(mq, pooled_.back()[size_t(jj) * size_t(w_) + size_t(ii)]);
          }
        out[size_t(j) * size_t(w_) + size_t(i)] = h == 1 ? q(m) : uint8_t(mq);
      }
    pooled_.push_back(std::move(out));
  }
}

namespace {

struct Setup {
  int nxy = 0, nyaw = 0, top = 0;
  size_t np = 0;
  std::vector<int> ci, cj;  // per yaw index (0 .. 2 nyaw), per point
  double res = 0, oc = 1, os = 0, ixy2 = 0, iyaw2 = 0, ik2 = 0;
};

Setup prepare(const DistanceField& df, const ScorePyramid& pyr, const std::vector<Eigen::Vector2d>& pts,
              const SearchWindow& win) {
  Setup s;
  s.res = df.resolution();
  s.nxy = std::max(0, int(std::ceil(win.xy_m / s.res)));
  s.nyaw = std::max(0, int(std::ceil(win.yaw_rad / win.yaw_step_rad)));
  s.np = pts.size();
  s.oc = std::cos(df.origin_yaw());
  s.os = std::sin(df.origin_yaw());
  s.ixy2 = 1 / (win.sigma_xy_m * win.sigma_xy_m);
  s.iyaw2 = 1 / (win.sigma_yaw_rad * win.sigma_yaw_rad);
  s.ik2 = win.prior_kappa > 0 ? 1 / (win.prior_kappa * win.prior_kappa) : 0;
  const int span = 2 * s.nxy + 1;
  while (s.top + 1 < pyr.levels() && (1 << s.top) < span) ++s.top;
  const int ny = 2 * s.nyaw + 1;
  s.ci.resize(size_t(ny) * s.np);
  s.cj.resize(size_t(ny) * s.np);
  for (int y = 0; y < ny; ++y) {
    const double yaw = win.center.yaw + (y - s.nyaw) * win.yaw_step_rad;
    const double c = std::cos(yaw), sn = std::sin(yaw);
    for (size_t k = 0; k < s.np; ++k) {
      const Eigen::Vector2d w(win.center.x + c * pts[k].x() - sn * pts[k].y(), win.center.y + sn * pts[k].x() + c * pts[k].y());
      const Eigen::Vector2d cc = df.to_cell(w);
      s.ci[size_t(y) * s.np + k] = int(std::lround(cc.x()));
      s.cj[size_t(y) * s.np + k] = int(std::lround(cc.y()));
    }
  }
  return s;
}

// The prior's largest value over offsets [d, d + w) (cells) per axis and the yaw offset.
double prior_max(const Setup& s, int di, int dj, int w, double dyaw) {
  if (s.ik2 == 0) return 1;
  auto closest = [&](int d) { return (d <= 0 && d + w - 1 >= 0) ? 0.0 : std::min(std::abs(d), std::abs(d + w - 1)) * s.res; };
  const double dx = closest(di), dy = closest(dj);
  const double m2 = (dx * dx + dy * dy) * s.ixy2 + dyaw * dyaw * s.iyaw2;
  return std::exp(-0.5 * m2 * s.ik2);
}

double exact_fit(const ScorePyramid& pyr, const Setup& s, int y, int di, int dj) {
  const int* ci = &s.ci[size_t(y) * s.np];
  const int* cj = &s.cj[size_t(y) * s.np];
  double sum = 0;
  for (size_t k = 0; k < s.np; ++k) sum += pyr.score(ci[k] + di, cj[k] + dj);
  return sum / double(s.np);
}

double bound_fit(const ScorePyramid& pyr, const Setup& s, int y, int di, int dj, int h) {
  if (h == 0) return exact_fit(pyr, s, y, di, dj);
  const int* ci = &s.ci[size_t(y) * s.np];
  const int* cj = &s.cj[size_t(y) * s.np];
  long sum = 0;
  for (size_t k = 0; k < s.np; ++k) sum += pyr.bound(h, ci[k] + di, cj[k] + dj);
  return double(sum) / (255.0 * double(s.np));
}

SearchCandidate make_candidate(const SearchWindow& win, const Setup& s, int y, int di, int dj, double fit, double score) {
  const double dx = di * s.res, dy = dj * s.res;
  SearchCandidate c;
  c.pose = {win.center.x + s.oc * dx - s.os * dy, win.center.y + s.os * dx + s.oc * dy,
            wrap_angle(win.center.yaw + (y - s.nyaw) * win.yaw_step_rad)};
  c.fit = fit;
  c.score = score;
  return c;
}

struct Node {
  int y, di, dj, h;
  double bound;
};

struct Bnb {
  const DistanceField& df;
  const ScorePyramid& pyr;
  const SearchWindow& win;
  const SearchOptions& opt;
  const Setup& s;
  std::vector<SearchCandidate> kept;
  SearchStats st;

  double threshold() const {
    double t = std::max(opt.min_score, kept.empty() ? -1 : opt.min_ratio * kept.front().score);
    if (int(kept.size()) >= std::max(1, opt.keep)) t = std::max(t, kept.back().score);
    return t;
  }
  void offer(const SearchCandidate& c) {
    const int k = std::max(1, opt.keep);
    for (auto& o : kept) {
      if (std::hypot(o.pose.x - c.pose.x, o.pose.y - c.pose.y) < opt.sep_xy_m &&
          std::abs(wrap_angle(o.pose.yaw - c.pose.yaw)) < opt.sep_yaw_rad) {
        if (c.score > o.score) o = c;
        std::sort(kept.begin(), kept.end(), [](const auto& a, const auto& b) { return a.score > b.score; });
        return;
      }
    }
    if (int(kept.size()) < k) kept.push_back(c);
    else if (c.score > kept.back().score) kept.back() = c;
    else return;
    std::sort(kept.begin(), kept.end(), [](const auto& a, const auto& b) { return a.score > b.score; });
  }
  void visit(const Node& n) {
    if (n.bound <= threshold()) return;
    const double dyaw = (n.y - s.nyaw) * win.yaw_step_rad;
    if (n.h == 0) {
      ++st.leaves;
      const double fit = exact_fit(pyr, s, n.y, n.di, n.dj);
      const double sc = fit * prior_max(s, n.di, n.dj, 1, dyaw);
      const SearchCandidate c = make_candidate(win, s, n.y, n.di, n.dj, fit, sc);
      if (opt.position_ok && !opt.position_ok(c.pose.x, c.pose.y)) return;
      offer(c);
      return;
    }
    const int c = 1 << (n.h - 1);
    Node ch[4];
    int m = 0;
    for (int b = 0; b < 2; ++b)
      for (int a = 0; a < 2; ++a) {
        const int di = n.di + a * c, dj = n.dj + b * c;
        if (di > s.nxy || dj > s.nxy) continue;
        ++st.nodes;
        ch[m++] = {n.y, di, dj, n.h - 1, bound_fit(pyr, s, n.y, di, dj, n.h - 1) * prior_max(s, di, dj, c, dyaw)};
      }
    std::sort(ch, ch + m, [](const Node& a, const Node& b) { return a.bound > b.bound; });
    for (int k = 0; k < m; ++k) visit(ch[k]);
  }
};

}  // namespace

std::vector<SearchCandidate> correlative_search(const DistanceField& df, const ScorePyramid& pyr,
                                                const std::vector<Eigen::Vector2d>& points, const SearchWindow& win,
                                                const SearchOptions& opt, SearchStats* stats) {
  if (points.empty()) return {};
  const Setup s = prepare(df, pyr, points, win);
  Bnb b{df, pyr, win, opt, s, {}, {}};
  std::vector<Node> top;
  const int w = 1 << s.top;
  for (int y = 0; y <= 2 * s.nyaw; ++y) {
    const double dyaw = (y - s.nyaw) * win.yaw_step_rad;
    for (int dj = -s.nxy; dj <= s.nxy; dj += w)
      for (int di = -s.nxy; di <= s.nxy; di += w) {
        ++b.st.nodes;
        top.push_back({y, di, dj, s.top, bound_fit(pyr, s, y, di, dj, s.top) * prior_max(s, di, dj, w, dyaw)});
      }
  }
  std::sort(top.begin(), top.end(), [](const Node& a, const Node& c) { return a.bound > c.bound; });
  for (const auto& n : top) b.visit(n);
  if (stats) *stats = b.st;
  return b.kept;
}

SearchCandidate correlative_search_exhaustive(const DistanceField& df, const ScorePyramid& pyr,
                                              const std::vector<Eigen::Vector2d>& points, const SearchWindow& win) {
  const Setup s = prepare(df, pyr, points, win);
  SearchCandidate best;
  best.score = -1;
  for (int y = 0; y <= 2 * s.nyaw; ++y) {
    const double dyaw = (y - s.nyaw) * win.yaw_step_rad;
    for (int dj = -s.nxy; dj <= s.nxy; ++dj)
      for (int di = -s.nxy; di <= s.nxy; ++di) {
        const double fit = exact_fit(pyr, s, y, di, dj);
        const double sc = fit * prior_max(s, di, dj, 1, dyaw);
        if (sc > best.score) best = make_candidate(win, s, y, di, dj, fit, sc);
      }
  }
  return best;
}

}  // namespace fploc::laser2d
