#include "fploc/relocalization/relocalizer.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "fploc/annf/annf.h"
#include "fploc/annf/baselines.h"
#include "fploc/annf/cache.h"

namespace fploc::reloc {

const char* to_string(RelocStatus s) {
  switch (s) {
    case RelocStatus::kFound: return "FOUND";
    case RelocStatus::kAmbiguous: return "AMBIGUOUS";
    case RelocStatus::kNoFit: return "NO_FIT";
  }
  return "?";
}

namespace {

double wrap(double a) { return std::remainder(a, 2 * M_PI); }

bool same_place(const Pose2& a, const Pose2& b, const RelocalizerConfig& c) {
  return std::hypot(a.x - b.x, a.y - b.y) < c.distinct_m && std::abs(wrap(a.yaw - b.yaw)) < c.distinct_deg * M_PI / 180;
}

struct Scored {
  double score;
  Pose2 pose;
};

}  // namespace

Relocalizer::Relocalizer(const FloorPlan& plan, const matcher::NearestLookup& lookup, RelocalizerConfig cfg)
    : lookup_(lookup), cfg_(cfg) {
  if (plan.elements.empty()) throw std::runtime_error("relocalizer: empty floor plan");
  if (!(cfg_.grid_m > 0) || !(cfg_.yaw_step_deg > 0) || !(cfg_.truncate_m > 0) || !(cfg_.distance_cell_m > 0) ||
      cfg_.max_points < 3 || cfg_.keep < 1 || cfg_.refine < 1)
    throw std::runtime_error("relocalizer: grid_m, yaw_step_deg, truncate_m, distance_cell_m must be > 0, "
                             "max_points >= 3, keep and refine >= 1");
  annf::AnnfOptions ao;
  ao.mode = annf::AnnfMode::kExact;
  ao.max_depth = 6;  // the grid reads cell centres; the exact field only needs to be exact there
  const std::shared_ptr<const annf::Annf> exact = annf::cached_annf(plan, ao);  // shared on disk (fploc/annf/cache.h)
  grid_ = std::make_unique<annf::DistanceGrid>(*exact, cfg_.distance_cell_m);
  const Box2 b = plan.bounds();
  for (double y = b.min.y() + 0.5 * cfg_.grid_m; y < b.max.y(); y += cfg_.grid_m)
    for (double x = b.min.x() + 0.5 * cfg_.grid_m; x < b.max.x(); x += cfg_.grid_m) {
      float d = 0;
      if (grid_->read({x, y}, &d) >= 0 && d >= cfg_.clearance_m) free_.emplace_back(x, y);
    }
}

Relocalizer::~Relocalizer() = default;

std::vector<uint8_t> Relocalizer::explained_points(const FeatureFrame& f, const Pose2& pose, int stride) const {
  std::vector<uint8_t> e;
  int ids[16];
  const auto& targets = lookup_.targets();
  for (size_t i = 0; i < f.points.size(); i += size_t(stride)) {
    const Eigen::Vector2d q = matcher::transform(pose, f.points[i].p);
    const int n = lookup_.candidates(q, ids, 16);
    double d = 1e9;
    for (int k = 0; k < n; ++k) d = std::min(d, distance(targets[size_t(ids[k])], q));
    e.push_back(d <= cfg_.inlier_m ? 1 : 0);
  }
  return e;
}

RelocResult Relocalizer::locate(const FeatureFrame& f, const std::optional<SearchRegion>& region) const {
  RelocResult out;
  const int n_all = int(f.points.size());
  const int stride = std::max(1, (n_all + cfg_.max_points - 1) / cfg_.max_points);
  std::vector<Eigen::Vector2f> pts;
  for (int i = 0; i < n_all; i += stride) pts.push_back(f.points[size_t(i)].p.cast<float>());
  out.points = int(pts.size());
  if (pts.size() < 10) {
    out.text = "too few features (" + std::to_string(n_all) + ")";
    return out;
  }
  // Yaws and the rotated point sets.
  const double step = cfg_.yaw_step_deg * M_PI / 180;
  std::vector<double> yaws;
  if (region && region->yaw_window_rad < M_PI) {
    for (double dy = -region->yaw_window_rad; dy <= region->yaw_window_rad + 1e-9; dy += step)
      yaws.push_back(wrap(region->center.yaw + dy));
  } else {
    for (double y = -M_PI; y < M_PI - 1e-9; y += step) yaws.push_back(y);
  }
  const size_t P = pts.size();
  std::vector<Eigen::Vector2f> rot(yaws.size() * P);
  for (size_t k = 0; k < yaws.size(); ++k) {
    const float c = float(std::cos(yaws[k])), s = float(std::sin(yaws[k]));
    for (size_t i = 0; i < P; ++i) rot[k * P + i] = {c * pts[i].x() - s * pts[i].y(), s * pts[i].x() + c * pts[i].y()};
  }
  std::vector<Eigen::Vector2d> cells;
  if (region) {
    for (const auto& c : free_)
      if ((c - Eigen::Vector2d(region->center.x, region->center.y)).norm() <= region->radius_m) cells.push_back(c);
    float d = 0;  // the region's own centre (off the lattice) is a hypothesis too
    if (grid_->read({region->center.x, region->center.y}, &d) >= 0 && d >= cfg_.clearance_m)
      cells.emplace_back(region->center.x, region->center.y);
  } else {
    cells = free_;
  }
  // Correlative search with pruning: a hypothesis stops as soon as it cannot enter the kept list. The
  // list keeps *distinct* places only (a better neighbour replaces a worse one), so one strong peak
  // cannot crowd out the second place of a symmetric plan.
  const float inv_t2 = float(1.0 / (cfg_.truncate_m * cfg_.truncate_m));
  std::vector<Scored> kept;
  double threshold = -1.0;  // lowest kept score once the list is full
  auto insert = [&](const Scored& h) {
    for (auto& k : kept)
      if (same_place(k.pose, h.pose, cfg_)) {
        if (h.score > k.score) k = h;
        return;
      }
    if (int(kept.size()) < cfg_.keep) {
      kept.push_back(h);
    } else {
      auto worst = std::min_element(kept.begin(), kept.end(), [](const Scored& a, const Scored& b) { return a.score < b.score; });
      *worst = h;
    }
    if (int(kept.size()) >= cfg_.keep)
      threshold = std::min_element(kept.begin(), kept.end(), [](const Scored& a, const Scored& b) { return a.score < b.score; })->score;
  };
  for (const auto& c : cells) {
    const float cx = float(c.x()), cy = float(c.y());
    for (size_t k = 0; k < yaws.size(); ++k) {
      ++out.hypotheses;
      const Eigen::Vector2f* r = &rot[k * P];
      float s = 0;
      bool pruned = false;
      for (size_t i = 0; i < P; ++i) {
        float d = 0;
        if (grid_->read(Eigen::Vector2d(r[i].x() + cx, r[i].y() + cy), &d) >= 0) s += std::max(0.f, 1.f - d * d * inv_t2);
        if ((i & 15) == 15 && double(s) + double(P - 1 - i) <= threshold) {
          pruned = true;
          break;
        }
      }
      if (pruned || double(s) <= threshold) continue;
      insert({double(s), Pose2{c.x(), c.y(), yaws[k]}});
    }
  }
  std::sort(kept.begin(), kept.end(), [](const Scored& a, const Scored& b) { return a.score > b.score; });
  // Distinct hypotheses, refined.
  std::vector<Scored> seeds;
  for (const auto& h : kept) {
    if (int(seeds.size()) >= cfg_.refine) break;
    if (std::none_of(seeds.begin(), seeds.end(), [&](const Scored& s) { return same_place(s.pose, h.pose, cfg_); }))
      seeds.push_back(h);
  }
  std::vector<std::vector<uint8_t>> explained;  // per refined candidate: which test points it explains
  const int tstride = std::max(1, (n_all + 799) / 800);
  // Coarse to fine: a correlative search at a fifth of the steps (and a tighter kernel) around each
  // seed, then single-frame registration from there.
  const double fine_t = std::max(cfg_.truncate_m / 3, 2 * cfg_.distance_cell_m);
  const float fine_inv_t2 = float(1.0 / (fine_t * fine_t));
  const double fstep = cfg_.grid_m / 5, fyaw = step / 5;
  for (auto& s : seeds) {
    Pose2 best_fine = s.pose;
    double best_score = -1;
    for (int a = -5; a <= 5; ++a) {
      const double yaw = s.pose.yaw + a * fyaw;
      const float c = float(std::cos(yaw)), sn = float(std::sin(yaw));
      for (int iy = -3; iy <= 3; ++iy)
        for (int ix = -3; ix <= 3; ++ix) {
          const float tx = float(s.pose.x + ix * fstep), ty = float(s.pose.y + iy * fstep);
          float sc = 0;
          for (const auto& p : pts) {
            float d = 0;
            if (grid_->read(Eigen::Vector2d(c * p.x() - sn * p.y() + tx, sn * p.x() + c * p.y() + ty), &d) >= 0)
              sc += std::max(0.f, 1.f - d * d * fine_inv_t2);
          }
          if (sc > best_score) {
            best_score = sc;
            best_fine = Pose2{tx, ty, wrap(yaw)};
          }
        }
    }
    s.pose = best_fine;
  }
  for (const auto& s : seeds) {
    const matcher::MatchResult m = register_frame(lookup_, f, s.pose, cfg_.registration);
    RelocHypothesis h{m.solved, s.score, m.fit, 0.0};
    // A local search answers within its region (a grid step's leeway): a seed whose refinement slid out of it
    // (along a corridor) is another place, and the region is where the robot can be.
    if (region && std::hypot(h.pose.x - region->center.x, h.pose.y - region->center.y) > region->radius_m + cfg_.grid_m)
      continue;
    std::vector<uint8_t> e = explained_points(f, h.pose, tstride);
    auto same = std::find_if(out.candidates.begin(), out.candidates.end(),
                             [&](const RelocHypothesis& o) { return same_place(o.pose, h.pose, cfg_); });
    if (same == out.candidates.end()) {
      out.candidates.push_back(h);
      explained.push_back(std::move(e));
    } else if (h.fit.num_inliers > same->fit.num_inliers) {
      *same = h;
      explained[size_t(same - out.candidates.begin())] = std::move(e);
    }
  }
  std::vector<size_t> order(out.candidates.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  auto count = [&](size_t i) { return std::count(explained[i].begin(), explained[i].end(), uint8_t(1)); };
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return count(a) != count(b) ? count(a) > count(b) : out.candidates[a].score > out.candidates[b].score;
  });
  {
    std::vector<RelocHypothesis> sorted;
    std::vector<std::vector<uint8_t>> ex;
    for (size_t i : order) {
      sorted.push_back(out.candidates[i]);
      ex.push_back(std::move(explained[i]));
    }
    out.candidates = std::move(sorted);
    explained = std::move(ex);
  }
  // Paired evidence of the best against each alternative (McNemar).
  for (size_t k = 1; k < out.candidates.size(); ++k) {
    int b = 0, c = 0;
    for (size_t i = 0; i < explained[0].size(); ++i) {
      b += explained[0][i] && !explained[k][i];
      c += !explained[0][i] && explained[k][i];
    }
    out.candidates[k].evidence = b + c > 0 ? double(b - c) * double(b - c) / double(b + c) : 0.0;
  }
  if (out.candidates.empty()) {
    out.text = "no hypothesis in the search region";
    return out;
  }
  const RelocHypothesis& b = out.candidates.front();
  out.pose = b.pose;
  out.fit = b.fit;
  char buf[200];
  if (b.fit.inlier_ratio < cfg_.min_inlier_ratio) {
    std::snprintf(buf, sizeof buf, "best fit explains %.0f %% of the features (< %.0f %%)", 100 * b.fit.inlier_ratio,
                  100 * cfg_.min_inlier_ratio);
    out.text = buf;
    return out;
  }
  for (size_t k = 1; k < out.candidates.size(); ++k) {
    const RelocHypothesis& r = out.candidates[k];
    if (r.fit.inlier_ratio < cfg_.min_inlier_ratio || r.evidence >= cfg_.min_evidence) continue;
    std::snprintf(buf, sizeof buf, "ambiguous: (%.2f, %.2f, %.0f deg) fits %.0f %% of the features too (evidence %.1f < %.1f)",
                  r.pose.x, r.pose.y, r.pose.yaw * 180 / M_PI, 100 * r.fit.inlier_ratio, r.evidence, cfg_.min_evidence);
    out.status = RelocStatus::kAmbiguous;
    out.text = buf;
    return out;
  }
  out.status = RelocStatus::kFound;
  std::snprintf(buf, sizeof buf, "found (%.2f, %.2f, %.1f deg), %.0f %% inliers, %lld hypotheses", b.pose.x, b.pose.y,
                b.pose.yaw * 180 / M_PI, 100 * b.fit.inlier_ratio, (long long)out.hypotheses);
  out.text = buf;
  return out;
}

}  // namespace fploc::reloc