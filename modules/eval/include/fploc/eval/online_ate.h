// ATE while a run is going on (the dashboard's running figure): estimates and ground truth arrive in
// any order, each estimate is matched to the ground-truth sample nearest in time within a tolerance (as
// `associate` does for files), an estimate re-published with the same stamp (the window optimizer)
// replaces its earlier error. Translation RMSE without alignment (Align::None of `ate`). Memory is
// bounded: the oldest samples are dropped beyond `max_samples` each.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>

namespace fploc::eval {

class OnlineAte {
 public:
  explicit OnlineAte(double match_tolerance_s = 0.002, size_t max_samples = 100000)
      : tol_us_(int64_t(match_tolerance_s * 1e6)), max_(max_samples) {}
  void add_estimate(int64_t utime, double x, double y, double z);
  void add_truth(int64_t utime, double x, double y, double z);
  // The position error of the estimate stamped `utime` [m], once matched.
  std::optional<double> error(int64_t utime) const;
  double rmse() const;  // NaN before the first match
  size_t count() const { return err_sq_.size(); }

 private:
  void match(int64_t t, const std::array<double, 3>& p);
  int64_t tol_us_;
  size_t max_;
  std::map<int64_t, std::array<double, 3>> est_, gt_;
  std::map<int64_t, double> err_sq_;
  double sum_ = 0;
};

}  // namespace fploc::eval
