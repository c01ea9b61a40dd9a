// Plane fit strategies of the segmenter: the dominant horizontal plane of a candidate set (the ceiling
// above the sensor, or the ground with `up` flipped). The paper's ring-seeded robust fit is RingPlaneFit;
// PCL's RANSAC variant is RansacPlaneFit (ransac_plane_fit.h, PCL stays in its .cpp).
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "fploc/segmentation/candidates.h"
#include "fploc/segmentation/segmenter_config.h"

namespace fploc::seg {

// Which plane a fit is for. The ceiling gives the attitude: its fit may spend extra work on accuracy.
enum class PlaneRole { kCeiling, kGround };

class PlaneFit {
 public:
  virtual ~PlaneFit() = default;
  virtual const char* name() const = 0;
  // Whether fit() reads Candidates::p (else only the float arrays; p is then not filled).
  virtual bool reads_points() const { return true; }
  // Fits the dominant plane of `c` above the sensor along `up`. `previous` (if non-null) is last frame's
  // plane in the same convention. Returns the plane with n pointing against `up` (into the room), or false.
  virtual bool fit(const Candidates& c, const Eigen::Vector3d& up, const Eigen::Vector4d* previous, PlaneRole role,
                   Eigen::Vector4d& plane) = 0;
  // Fits that refined last frame's plane without searching for a start (diagnostics, tests).
  virtual int64_t steady_fits() const { return 0; }
  // What one fit carries to the next (and the diagnostics) as after construction; scratch kept (Segmenter::reset).
  virtual void reset() {}
};

// The paper's fit: max-range seeds on the top K_r rings, linear regression, IRLS (Tukey), see
// ring_plane_fit.cpp.
class RingPlaneFit : public PlaneFit {
 public:
  explicit RingPlaneFit(const SegmenterConfig& cfg) : cfg_(cfg) {}
  const char* name() const override { return "rings"; }
  bool reads_points() const override { return false; }
  bool fit(const Candidates& c, const Eigen::Vector3d& up, const Eigen::Vector4d* previous, PlaneRole role,
           Eigen::Vector4d& plane) override;

 private:
  struct Fit {
    Eigen::Vector4d pl;
    double sigma;
    bool joined = false;  // stopped on reaching the other refinement's result (refine's `join`): pl is that one
    double cut = 0;       // the IRLS cut-off it ended with (0: not a refinement)
  };
  void pick_seeds(const Candidates& c, const Eigen::Vector3f& up);
  bool search(const Candidates& c, const Eigen::Vector3d& up, const Eigen::Vector4d* previous, PlaneRole role,
              std::optional<Fit>& res1);
  bool choose_start(const Candidates& c, const Eigen::Vector3d& up, const Eigen::Vector4d* previous,
                    Eigen::Vector4d& start);
  // Support of `pl` on `sub`, a subsample of the candidates (every stride-th), scaled by the stride.
  double score_band(const PointsSoa& sub, size_t stride, const Eigen::Vector4d& pl, float band) const;
  // IRLS from `start` over the candidates (xs_/ys_/zs_); the cut-off shrinks from first_cut down to min_cut
  // (fixed: stays at first_cut). With `join` (another refinement's result on the same candidates): once the
  // cut-off is near the one `join` ended with and the iterate lies within kJoinNormal / kJoinDistM of it, the
  // refinement stops and returns `join` with joined set (from there it converges to the same plane). A fixed
  // cut-off's refit started at `join`'s plane returns it joined when its first step is tiny (it stays there).
  std::optional<Fit> refine(const Eigen::Vector3d& up, Eigen::Vector4d start, double first_cut, double min_cut,
                            bool fixed, const Fit* join = nullptr);

  SegmenterConfig cfg_;
  std::vector<int> seeds_, all_seeds_;
  struct SeedKey {  // pick_seeds: a sector maximum's range and index (src/seed_order.h)
    float range;
    int index;
  };
  std::vector<SeedKey> seed_keys_;
  std::vector<float> sector_best_;
  std::vector<int> sector_idx_;
  std::vector<float> seed_rv_;  // a seed ring's ranges, -inf below the seed height (pick_seeds)
  std::vector<int> sector_of_col_;  // azimuth sector of each staggered column (pick_seeds)
  int sector_cols_s_ = 0;
  // The current fit's candidates (Candidates' float arrays, NaN-padded to np_, a multiple of 4).
  const float *xs_ = nullptr, *ys_ = nullptr, *zs_ = nullptr;
  size_t np_ = 0, n_ = 0;
  const Candidates* cand_ = nullptr;  // them (for their bounding boxes)
  PointsSoa band_, band_sub_, sub_start_, sub_final_;  // band_: relative to the refinement's reference point
  std::vector<float> scratch_;  // refine: the band's residuals in histogram bins
  size_t start_stride_ = 1, final_stride_ = 1;  // of the current fit (Candidates, else the reference strides)
  // Per role: fits left that refine last frame's plane alone (SegmenterConfig::start_recheck_scans), and the
  // plane the last fit of that role returned (a steady fit needs `previous` to be it: consecutive accepted fits).
  struct Steady {
    int left = 0;
    Eigen::Vector4d plane = Eigen::Vector4d::Zero();
    double support = 0;  // its support (score_band at the inlier threshold)
  };
  Steady steady_[2];
  int64_t steady_fits_ = 0;

 public:
  // Fits that refined last frame's plane alone (diagnostics, tests).
  int64_t steady_fits() const override { return steady_fits_; }
  void reset() override {
    steady_[0] = steady_[1] = Steady{};
    steady_fits_ = 0;
  }
};

}  // namespace fploc::seg
