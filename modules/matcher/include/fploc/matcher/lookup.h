// Correspondence look-up behind the registration residuals: given a point in the plan frame, which
// targets (floor-plan elements, or points sampled on the plan) may be its nearest one.
//
// Implementations (selected by name, see make_lookup):
//   "brute-force"  the exact nearest element (O(#elements) per query)
//   "kdtree"       nearest of points sampled on the plan (nanoflann): point-to-point registration, the
//                  approach the paper's Section III argues against
//   "annf-exact" / "annf-paper"  the ANNF (modules/annf), see annf_lookup.h
//
// Targets are Elements: a point sample is a degenerate segment (a == b), so one residual type serves all.
#pragma once
#include <Eigen/Core>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "fploc/floorplan/plan.h"

namespace fploc::matcher {

// A target's geometry prepared for the residuals: segments with their unit direction and length (no
// division per evaluation); circles/arcs as in Element.
struct TargetGeom {
  ElementKind kind = ElementKind::kSegment;
  Eigen::Vector2d a = Eigen::Vector2d::Zero(), b = Eigen::Vector2d::Zero();
  Eigen::Vector2d u = Eigen::Vector2d::Zero();  // segment: (b - a) / len (zero for a point)
  double len = 0;
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  double r = 0, a0 = 0, a1 = 0;
};

class NearestLookup {
 public:
  virtual ~NearestLookup() = default;
  // targets() prepared for the residuals (built on first use, thread-safe).
  const std::vector<TargetGeom>& geometry() const;
  // What candidate ids refer to.
  virtual const std::vector<Element>& targets() const = 0;
  // Writes up to `max` candidate target ids for point p (plan frame) to out; returns how many. The
  // residual uses the closest of them (re-evaluated as the estimate moves inside one solve).
  virtual int candidates(const Eigen::Vector2d& p, int* out, int max) const = 0;
  virtual std::string name() const = 0;
  // False for point targets: the PCA group rule (one group, one element) does not apply.
  virtual bool element_targets() const { return true; }

 private:
  mutable std::once_flag geom_once_;
  mutable std::vector<TargetGeom> geom_;
};

// Exact nearest element by brute force.
class BruteForceLookup : public NearestLookup {
 public:
  explicit BruteForceLookup(const FloorPlan& plan) : plan_(plan) {}
  const std::vector<Element>& targets() const override { return plan_.elements; }
  int candidates(const Eigen::Vector2d& p, int* out, int max) const override;
  std::string name() const override { return "brute-force"; }

 private:
  const FloorPlan& plan_;
};

// Nearest of points sampled every `spacing_m` along every element (nanoflann KD-tree).
class KdTreeLookup : public NearestLookup {
 public:
  KdTreeLookup(const FloorPlan& plan, double spacing_m = 0.05);
  ~KdTreeLookup() override;
  const std::vector<Element>& targets() const override { return samples_; }
  int candidates(const Eigen::Vector2d& p, int* out, int max) const override;
  std::string name() const override { return "kdtree"; }
  bool element_targets() const override { return false; }
  size_t size() const { return samples_.size(); }

 private:
  struct Impl;
  std::vector<Element> samples_;
  std::unique_ptr<Impl> impl_;
};

// Samples points along an element every spacing_m (both ends included).
std::vector<Eigen::Vector2d> sample_element(const Element& e, double spacing_m);

}  // namespace fploc::matcher