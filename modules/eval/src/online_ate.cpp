#include "fploc/eval/online_ate.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace fploc::eval {

void OnlineAte::match(int64_t t, const std::array<double, 3>& p) {
  auto best = gt_.end();
  int64_t best_d = tol_us_ + 1;
  for (auto it = gt_.lower_bound(t - tol_us_); it != gt_.end() && it->first <= t + tol_us_; ++it) {
    const int64_t d = std::llabs(it->first - t);
    if (d < best_d) best_d = d, best = it;
  }
  if (auto old = err_sq_.find(t); old != err_sq_.end()) {
    sum_ -= old->second;
    err_sq_.erase(old);
  }
  if (best == gt_.end()) return;
  const auto& g = best->second;
  const double e = (p[0] - g[0]) * (p[0] - g[0]) + (p[1] - g[1]) * (p[1] - g[1]) + (p[2] - g[2]) * (p[2] - g[2]);
  err_sq_[t] = e;
  sum_ += e;
}

void OnlineAte::add_estimate(int64_t t, double x, double y, double z) {
  est_[t] = {x, y, z};
  match(t, est_[t]);
  while (est_.size() > max_) {
    auto first = est_.begin();
    if (auto e = err_sq_.find(first->first); e != err_sq_.end()) {
      sum_ -= e->second;
      err_sq_.erase(e);
    }
    est_.erase(first);
  }
}

void OnlineAte::add_truth(int64_t t, double x, double y, double z) {
  gt_[t] = {x, y, z};
  while (gt_.size() > max_) gt_.erase(gt_.begin());
  // Estimates that arrived before their ground truth.
  for (auto it = est_.lower_bound(t - tol_us_); it != est_.end() && it->first <= t + tol_us_; ++it)
    if (!err_sq_.count(it->first)) match(it->first, it->second);
}

std::optional<double> OnlineAte::error(int64_t t) const {
  auto e = err_sq_.find(t);
  if (e == err_sq_.end()) return std::nullopt;
  return std::sqrt(e->second);
}

double OnlineAte::rmse() const { return err_sq_.empty() ? NAN : std::sqrt(std::max(0.0, sum_) / double(err_sq_.size())); }

}  // namespace fploc::eval
