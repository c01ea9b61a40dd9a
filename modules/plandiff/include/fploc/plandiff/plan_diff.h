// Plan-change detection: where does the building no longer match its floor plan? Fed with registered
// scans (2D wall features in the sensor frame + the pose that places them on the plan), it keeps, per
// plan element, evidence over the whole run:
//   seen      points on the element where the plan puts it;
//   missing   in view (range, incidence), not hidden by another plan element nor by anything nearer that
//             was measured (ray cast from the pose), and yet no point on it, frame after frame;
//   moved     its points sit consistently at an offset along its normal (how far: the median offset);
// a global drawing-scale error (the plan drawn or scanned at a slightly wrong scale);
// and, for points near no plan element, a grid of cells hit in several frames from which straight runs
// (RANSAC lines split at gaps) are reported as new structure.
// Pieces (a doorway moved along its wall: the wall lost a piece to the new opening and grew over the
// old one): a missing part is a run of an element's probes that were expected, not seen, and seen
// *through* (something measured beyond them in their bearing, frame after frame); an extension is new
// straight structure continuing a wall beyond its drawn end (points collinear with the wall past its
// end go to the new-structure grid; such runs are reported from ext_min_length_m, with `extends`).
// No transport: the node (nodes/plan_diff) and `fploc map diff` feed it.
//
//   fploc::plandiff::PlanDiff d(plan);
//   for each scan: d.add_frame(x, y, yaw, points_in_sensor_frame);
//   fploc::plandiff::Diff r = d.result();  write_json(r, plan, out); write_dxf(r, plan, out);
#pragma once
#include <Eigen/Core>
#include <Eigen/Dense>
#include <cstdint>
#include <iosfwd>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

#include "fploc/floorplan/plan.h"
#include "fploc/plandiff/drawing_scale.h"
#include "fploc/plandiff/wall_refinement.h"

namespace fploc::plandiff {

struct Options {
  double min_range_m = 0.5, max_range_m = 12.0;
  double assoc_m = 0.35;            // a point within this of an element observes it
  // ... if the straight structure it lies on runs along the element: a point whose neighbours in its scan (within
  // dir_radius_m, >= dir_min_points, straight: smallest / largest PCA eigenvalue <= dir_max_flatness) form a line
  // more than assoc_max_angle_deg off the element's direction there observes another element or nothing (new
  // structure): a partition built across where a removed wall was drawn, furniture left where it stood, is not
  // that wall seen. 0: no direction test. Segments shorter than 2 dir_radius_m (jambs) are not judged. (The
  // drawing-scale estimate keeps the plain nearest element.)
  double assoc_max_angle_deg = 10;
  double dir_radius_m = 0.3;
  int dir_min_points = 5;
  double dir_max_flatness = 0.05;
  double probe_step_m = 0.25;       // visibility probes along each element
  double bin_deg = 0.75;            // bearing bins of a scan (visibility / occlusion test)
  double min_incidence_deg = 25;    // probes seen at a more grazing angle are not expected
  double occlusion_margin_m = 0.4;  // a measured point this much nearer than a probe hides it
  int min_frames = 5;               // evidence over at least this many frames before a verdict
  double missing_seen_ratio = 0.08; // seen / expected probe observations below this: missing
  int missing_min_expected = 30;    // ... over at least this many expected probe observations
  double moved_min_m = 0.07;        // |median offset| at least this: moved
  // A scan's offset of an element: the median of the cluster of its points' offsets (split at gaps larger than
  // offset_cluster_gap_m) farthest from the sensor that holds >= offset_cluster_share of them: shelves and furniture
  // stand in front of a wall, not behind it (their faces within assoc_m of the drawn line pulled a scan's median
  // towards the sensor). 0: the plain median.
  double offset_cluster_gap_m = 0.06;
  double offset_cluster_share = 0.2;
  double moved_max_spread_m = 0.05; // ... and the per-frame offsets agree (MAD) within this
  double moved_min_length_m = 0.5;  // ... for segments at least this long (a door jamb's end is not a wall)
  // ... and |offset| - moved_z sigma >= moved_min_m (sigma: PlanDiff::offset_sigma): a wall a few cm off as
  // built, seen with a spread of offsets, is not called moved on an offset its uncertainty explains.
  double moved_z = 2.0;
  double moved_pose_sigma_m = 0.01;   // the localizer's error along the wall normal (does not average out)
  // With the localizer's pose covariance (add_frame's pose_cov): the pose part of an element's offset sigma is
  // the mean over its scans of the pose's variance along the wall's normal at its points (translation along
  // the normal and yaw times the lever arm to the points), at least moved_pose_sigma_m; false: that alone.
  bool moved_pose_covariance = true;
  // A segment is called moved only when each half of it (t < 0.5, t >= 0.5 along it) was measured in >= min_frames
  // scans (>= 3 points of that half) and each half's median offset passes the same test as the whole: a wall
  // standing askew (one end a few cm off, the other 10) or seen near one end only is not a wall moved as a whole.
  bool moved_both_halves = true;
  double moved_max_looks = 30;        // the scans count as at most this many independent looks
  // Change evidence (seen, missing, moved, new, missing parts) only from scans whose pose the localizer calls good:
  // add_frame's pose_ok (status OK: not POOR / LOST) and, with a covariance, a horizontal sigma (the larger axis)
  // <= max_pose_sigma_m and a yaw sigma <= max_pose_yaw_sigma_deg. A scan placed 0.4 m off paints the walls it sees
  // as moved and new structure beside them. The other scans still count for the drawing scale (as before).
  // 0: no limit.
  double max_pose_sigma_m = 0.05;
  double max_pose_yaw_sigma_deg = 1.0;
  // An element otherwise seen whose missing parts cover at least this share of its length is missing as a whole
  // (what was still seen there is something else standing where it was drawn: furniture, a partition's end).
  double missing_part_share = 2.0 / 3.0;
  double new_cell_m = 0.05;         // grid of unexplained points
  int new_min_frames = 5;           // a cell hit in at least this many frames ...
  double new_min_hit_ratio = 0.3;   // ... and whose view cell was hit in this share of the scans that had it
  double new_view_cell_m = 0.25;    // in view (nothing measured in front) is static structure
  double new_min_length_m = 0.8;    // shortest new wall reported
  // Height of new structure (add_frame's `heights`: the segmenter's 3D wall points). A new run is a wall only when
  // >= new_tall_share of its cells held points >= new_min_height_m above the floor in >= new_tall_min_frames scans;
  // a run whose cells were hit, in >= new_min_frames scans each, from where the sensor's highest beam passed above
  // new_min_height_m there (its range times the scan's steepest upward wall point) or above the structure's top (its
  // points there end >= 0.15 m + 5 % of the range below that beam), and that is not tall, is
  // low structure (Diff::low: a table, a cabinet, a bench), with the highest point seen on it. Runs that could not
  // be told (no heights, or never seen from far enough) stay new walls (NewStructure::height kUnknown). 0: off.
  double new_min_height_m = 1.8;
  int new_tall_min_frames = 2;
  double new_tall_share = 0.3;
  double new_low_checkable_share = 0.5;  // ... of its cells checkable for a run to be called low
  // A new wall is seen at once: its cells hit in one scan cover >= new_min_span_m of it without a gap wider than
  // new_max_gap_m (or 0.8 of its length, if shorter), in >= new_min_frames scans and in >= new_min_span_share of the
  // scans that hit it. A person pacing back and forth along a line leaves a straight trail
  // of cells hit in many scans, but covers no more than its own width (~0.45 m) at a time. Not asked of a wall's
  // continuation (extends >= 0). 0: off.
  double new_min_span_m = 0.6;
  double new_min_span_share = 0.2;
  double new_line_tol_m = 0.05;
  double new_max_gap_m = 0.3;
  double scale_max_offset_m = 0.1;  // points this close to their wall enter the drawing-scale estimate
  // Missing parts of an element otherwise seen: runs of probes each expected in >= part_min_expected frames,
  // seen through (a point >= part_through_m beyond it in its bearing) in >= part_min_through of them, and
  // seen in < part_seen_ratio of the frames that measured either.
  int part_min_expected = 10;
  int part_min_through = 5;
  double part_seen_ratio = 0.4;
  double part_through_m = 0.3;
  // Extensions: points within ext_lateral_m of a segment's line, >= ext_min_beyond_m past its end and not
  // within ext_clear_m of another element, are unexplained (new-structure grid); a run collinear with the
  // segment starting within ext_touch_m of its end is reported from ext_min_length_m (else new_min_length_m).
  double ext_lateral_m = 0.05;
  double ext_min_beyond_m = 0.05;
  double ext_clear_m = 0.08;
  double ext_touch_m = 0.35;
  double ext_min_length_m = 0.3;
  // As-built refinement (Diff::refined): every scan's median offset of each wall it sees, at the mean
  // position of its points along the wall, is (1 - t) o_a + t o_b minus the scan's registration error
  // (x, y, yaw, eliminated per scan); o_a, o_b (each segment's offset at its ends) are solved over the run
  // with a prior N(0, refine_prior_m) per end against refine_obs_sigma_m per observation.
  double refine_prior_m = 0.05;
  double refine_obs_sigma_m = 0.01;
  int refine_min_points = 5;          // points of the wall in the scan for an observation
  bool refine_ends = false;           // report each end's offset (else the wall's mean offset at both: the
                                      // difference, a wall's rotation, is poorly observed and was measured to hurt)
  double refine_min_info = 3;         // ends with this much information (in observations at that end, after the
                                      // scans' errors) are reported, else the wall's mean offset if it has as
                                      // much, else the wall is left as drawn
};

enum class Status : uint8_t { kUnobserved = 0, kSeen = 1, kMissing = 2, kMoved = 3 };
const char* status_name(Status s);

struct ElementDiff {
  int id = -1;
  Status status = Status::kUnobserved;
  double offset_m = 0;        // median signed offset along the left normal (segments) / radially (circles)
  double offset_spread_m = 0; // MAD of the per-frame offsets
  double offset_sigma_m = 0;  // its uncertainty (PlanDiff::offset_sigma)
  double pose_sigma_m = 0;    // the localizer's pose sigma along its normal (mean variance over its scans; 0: not given)
  double half_offset_m[2] = {0, 0};  // segments: the median offset of each half (a -> mid, mid -> b) ...
  int half_frames[2] = {0, 0};       // ... over this many scans
  int frames_with_points = 0;
  int frames_expected = 0;    // frames in which at least one probe was expected visible
  int64_t probes_expected = 0, probes_seen = 0;
  double seen_ratio() const { return probes_expected ? double(probes_seen) / double(probes_expected) : 0.0; }
};

enum class Height : uint8_t { kUnknown = 0, kTall = 1, kLow = 2 };
const char* height_name(Height h);  // "unknown", "tall", "low"

struct NewStructure {
  Eigen::Vector2d a, b;
  Height height = Height::kUnknown;  // Options::new_min_height_m
  double top_m = std::numeric_limits<double>::quiet_NaN();  // highest point seen on it above the floor (NaN: none)
  int extends = -1;           // the plan segment this run continues beyond its drawn end (-1: none)
  int cells = 0;
  int min_frames = 0;         // frames that hit its least-seen cell
  double rms_m = 0;           // of the cells about the line
  double length() const { return (b - a).norm(); }
};

// A piece of a plan segment that is gone (where the plan draws it), the rest of the element being there.
struct MissingPart {
  int element = -1;
  Eigen::Vector2d a, b;
  int64_t expected = 0, seen = 0, through = 0;  // probe observations over the piece
  double length() const { return (b - a).norm(); }
};


struct Diff {
  std::vector<ElementDiff> elements;  // one per plan element
  std::vector<NewStructure> added;    // new walls: tall, or height not told
  std::vector<NewStructure> low;      // new straight structure seen only below Options::new_min_height_m
  int height_frames = 0;              // evidence scans that came with heights (0: heights not checked)
  std::vector<MissingPart> missing_parts;
  int frames = 0;
  int evidence_frames = 0;  // of them, those whose pose was good enough for change evidence (Options::max_pose_sigma_m)
  // Drawing scale: the building is (1 + scale_error) times the plan (0.005: the drawing is 0.5 % too small),
  // from every point's offset against its distance to the sensor along the wall's normal, each scan's
  // registration bias eliminated. 0 with scale_points 0 when there was too little to tell.
  double scale_error = 0, scale_sigma = 0;
  int64_t scale_points = 0;
  std::vector<RefinedSegment> refined;  // segments observed in >= min_frames scans (empty: too little yet)
  int count(Status s) const;
};

class PlanDiff {
 public:
  explicit PlanDiff(FloorPlan plan, Options o = {});
  // One registered scan: pose of the sensor on the plan, wall points in the sensor frame (metres); pose_cov:
  // the pose's x, y, yaw covariance (the localizer's, optional: see Options::moved_pose_covariance); pose_ok: the
  // localizer's status is OK (false: POOR; see Options::max_pose_sigma_m). A pose that is not finite is ignored
  // (no frame).
  // heights (optional): the scan's wall points in the gravity-levelled sensor frame (x, y as the 2D points; z up
  // from the sensor) and the sensor's height above the floor: how tall the new structure is (Options::new_min_height_m).
  struct Heights {
    std::vector<Eigen::Vector3f> points;
    double sensor_z = 0;
  };
  void add_frame(double x, double y, double yaw, const std::vector<Eigen::Vector2f>& points,
                 const Eigen::Matrix3d* pose_cov = nullptr, bool pose_ok = true, const Heights* heights = nullptr);
  int evidence_frames() const { return evidence_frames_; }
  Diff result() const;
  int frames() const { return frames_; }
  const FloorPlan& plan() const { return plan_; }
  const Options& options() const { return o_; }

 private:
  struct Probe {
    Eigen::Vector2d p;
    Eigen::Vector2d n;  // outward normal at the probe (circles) / the wall normal (segments)
    int element;
  };
  struct Acc {
    std::vector<float> frame_offsets;  // per-frame median offset
    std::vector<float> half_offsets[2];  // segments: per-frame median offset of each half
    double pose_var = 0;               // sum over those frames (with a pose covariance) of the pose variance
    int pose_frames = 0;               // along the normal, and how many
    int frames_expected = 0;
    int64_t expected = 0, seen = 0;
  };
  struct Cell {
    int frames = 0, last_frame = -1, points = 0, in_view = 0;
    int tall_frames = 0, checkable_frames = 0;  // new-structure cells: scans with a point >= new_min_height_m there /
    float top_m = -1;                           // that could have seen one; the highest point seen there
    std::vector<int> hit_frames;  // new-structure cells: the frames that hit it (the first kMaxHitFrames)
  };
  static constexpr size_t kMaxHitFrames = 256;
  double offset_sigma(const ElementDiff& e) const;
  bool halves_moved(const ElementDiff& e) const;
  // dir: the local direction of the structure p lies on (unit; nullptr: none known); candidates not along it are
  // skipped (Options::assoc_max_angle_deg).
  int nearest(const Eigen::Vector2d& p, double* signed_offset, bool* inside, const Eigen::Vector2d* sensor,
              const Eigen::Vector2d* dir = nullptr) const;
  bool along(const Element& e, const Eigen::Vector2d& p, const Eigen::Vector2d& dir) const;
  bool extends_beyond_end(const Eigen::Vector2d& p) const;
  int extended_element(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const;
  bool plan_blocks(const Eigen::Vector2d& o, const Eigen::Vector2d& q, int skip) const;
  // A probe's look from s is blocked by another plan element: at the probe, or (segments) at either end of the
  // stretch of the element it stands for (probe_step_m).
  bool stretch_blocked(const Eigen::Vector2d& s, const Probe& pr) const;
  void cells_of(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi, std::vector<int>& out) const;

  FloorPlan plan_;
  Options o_;
  std::vector<Probe> probes_;
  std::vector<int> probe_expected_, probe_seen_, probe_through_;  // per probe
  std::vector<Acc> acc_;
  std::unordered_map<int64_t, Cell> cells_;  // new_cell_m: where
  std::unordered_map<int64_t, Cell> view_;   // new_view_cell_m: hit in how many of the scans that saw it
  int frames_ = 0;
  int evidence_frames_ = 0;  // of them, those that gave change evidence
  int height_frames_ = 0;    // evidence frames with heights
  DrawingScale scale_;
  WallRefinement refine_;
  // Uniform grid of elements (1 m cells, bounding boxes grown by assoc_m) for the point association.
  Eigen::Vector2d gmin_;
  int gx_ = 0, gy_ = 0;
  double gcell_ = 1.0;
  std::vector<std::vector<int>> grid_;
};

// {"frames", "evidence_frames", "summary": {"seen", "missing", "moved", "unobserved", "new", "low", "missing_parts"}, "scale": {"error", "sigma", "points"},
//  "elements": [{"id", "status",
//  "offset_m", "offset_spread_m", "offset_sigma_m", "seen_ratio", "frames_expected", "frames_with_points", "a", "b" | "c", "r"}],
//  "heights_checked", "height_frames",
//  "new": [{"a", "b", "length_m", "cells", "min_frames", "rms_m", "extends", "height", "top_m"}], "low": [same],
//  "missing_parts": [{"id", "a", "b", "length_m", "seen_ratio", "through_ratio"}],
//  "refined": [{"id", "offset_a", "offset_b", "frames"}]}   (elements: only those not
//  "seen" unless all_elements)
void write_json(const Diff& d, const FloorPlan& plan, std::ostream& out, bool all_elements = false);
// For people: one summary line ("26 seen, 2 missing, 0 moved, 16 unobserved, 4 new, 0 low, 1 missing part; drawing scale
// +0.48 % +- 0.05 % (N points)" or "drawing scale: too little to tell"), then one line per flagged item: each
// missing / moved element (id, layer, verdict, offset, length, where), each missing part, each new run. The
// caller prefixes the first line (fploc map diff: "N scans of LOG against PLAN: ").
void write_text(const Diff& d, const FloorPlan& plan, std::ostream& out);
// ASCII DXF (AC1009, $INSUNITS 6 = metres) with a LAYER table: FPLOC-PLAN (the plan, grey),
// FPLOC-MISSING (red: missing elements and missing parts where the plan has them), FPLOC-MOVED (yellow: moved elements
// where they were seen), FPLOC-NEW (green: new structure), FPLOC-LOW (cyan: new straight structure seen only below
// Options::new_min_height_m: furniture). LINE and CIRCLE entities only.
void write_dxf(const Diff& d, const FloorPlan& plan, std::ostream& out);

}  // namespace fploc::plandiff
