// The segmenter's fixed numbers (not options: they follow from the sensor, the statistics or the numerics),
// named in one place. Internal header of modules/segmentation.
#pragma once
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace fploc::seg::k {

constexpr double kDeg = M_PI / 180.0;

// ---- point preparation / candidates ----
// Seeds and RANSAC points must lie this far above the sensor along the gravity prior [m].
constexpr float kMinSeedHeightM = 0.2f;

// ---- the reference sensor the options and strides are stated for (beam_scaling.cpp) ----
constexpr int kRefBeams = 64;               // OS-1-64
constexpr int kRefWidth = 1024;             // 1024 columns per frame
constexpr double kRefRingSpacingDeg = 33.2 / 63;  // its rings' altitude spacing
constexpr double kRefSteepRingDeg = 8.3;    // its median upper ring's altitude (half of +16.6 deg)
constexpr double kRefSteepShare = 0.5;      // share of its upper rings at or above that
constexpr int kMinSeedRings = 2;            // a sparse sensor still seeds from two rings
constexpr int kMinPlaneInliersFloor = 30;   // a plane needs at least this many inliers on any sensor

// ---- ring plane fit (ring_plane_fit.cpp) ----
constexpr int kMinCandidatePoints = 10;     // fewer candidates: no fit
constexpr int kMinSectors = 4;              // at least this many azimuth sectors per seed ring
constexpr size_t kMinSeedsKept = 3;         // seeds kept per ring at least
constexpr int kSeedTrimRounds = 3;          // linear regression rounds (2 trims)
constexpr double kSeedTrimMinM = 0.05;      // trim cut-off at least this [m]
constexpr double kSeedTrimSigmas = 3.0;     // trim at this many robust sigmas
constexpr double kMadToSigma = 1.4826;      // median |r| -> sigma (Gaussian)
constexpr size_t kStartStride = 24;         // start selection: ~1.4k of 32k half-ring returns (reference sensor)
constexpr size_t kFinalStride = 3;          // support of refined planes: every 3rd return (reference sensor)
constexpr uint32_t kTripletSeed = 12345u;   // deterministic triplet sampling (LCG)
constexpr double kMinTripletNormal = 1e-3;  // |(b-a) x (q-a)| below this: degenerate triplet
constexpr int kScaleBins = 256;             // histogram of |r| for the robust scale
constexpr double kTukeyC = 4.685;           // Tukey biweight cut-off in robust sigmas (95 % efficiency)
constexpr double kMinCutM = 0.02;           // the shrinking cut-off stops here [m]
constexpr size_t kShrinkSubsample = 3;      // while the cut-off shrinks, every 3rd band point
constexpr double kConvergedNormal = 1e-5;   // IRLS converged: normal change (0.0006 deg)
constexpr double kConvergedDistM = 1e-4;    // and distance change (0.1 mm)
// A second refinement (from last frame's plane) whose iterate, with its cut-off settled, lies this close to the
// first refinement's result stops there and is taken as that result: the IRLS is a contraction near its fixed
// point, and both refinements' results were measured within 0.0023 deg / 0.3 mm of each other in every such
// case (24 simulated frames), while refinements that end on different planes end 0.01-1 deg apart.
constexpr double kJoinNormal = 1.75e-4;     // normal difference (0.01 deg)
constexpr double kJoinDistM = 1e-3;         // and distance difference (1 mm)
constexpr double kJoinCutRatio = 1.25;      // with a cut-off at most this times the one the first ended with
constexpr double kStillStepFraction = 1.0 / 3;  // a refit's first step below this x kJoin*: it stays (see refine)
constexpr double kSelectBandSigmas = 3.0;   // choosing between refinements: soft band at 3 robust sigmas
constexpr double kSelectBandMinM = 0.01;    // of at least 1 cm
// A plane followed steadily (SegmenterConfig::start_recheck_scans): last frame's plane refined alone ends the
// following when it moves more than this (a step to another surface, a start the search would have to find).
constexpr double kSteadyStepDeg = 1.0;
constexpr double kSteadyStepM = 0.05;
// ... or when its support falls below this share of the last fit's (a ceiling step: a slice of the walls at the old
// height fits as a plane, with a fraction of the ceiling's returns).
constexpr double kSteadyMinSupport = 0.8;
constexpr double kTightMinCutM = 0.01;      // tight ceiling refit cut-off at least 1 cm
constexpr double kMinBeyondRatio = 1e-3;    // guards 1 / max_beyond_ratio

// ---- acceptance of planes (segmenter.cpp) ----
constexpr double kMinCeilingDistM = 0.2;    // a ceiling closer than this to the sensor is not one
constexpr double kMinGroundDistM = 0.1;
constexpr double kMaxGroundTiltDeg = 5.0;
constexpr double kKinkFitOffDeg = 0.3;       // ground_kink.cpp: the ring fit this far off the followed surface: replaced   // ground normal vs the ceiling's (or prior) up
constexpr double kSweepSkewDeg = 0.05;       // ground_kink.cpp: the sweep's translation tilts the followed surface's fit
                                             // this much (plane fits of a floor: a few hundredths): de-skewed
constexpr double kFollowRateTauS = 0.3;      // ground_kink.cpp: low-pass of the sensor's speed off the followed surface
constexpr double kFollowRateMaxMs = 1.0;     // ... a faster change of its distance is a jump (another fit), not motion
constexpr double kCeilingPriorAgreeDeg = 2.0;  // ceiling this close to the prior: the ground is fitted around it
constexpr double kRefitLevelDeg = 1.0;  // a ground found around gravity off a slope: within this of level

// ---- gravity fusion (gravity_fusion.cpp) ----
// On a slope, not turning: the accelerometer's pull on the tilt across the slope (no platform acceleration
// there) [s]; along the slope it is accel_tau_s (the platform's accelerations along its path average out).
constexpr double kCrossSlopeAccelTauS = 2.0;

// ---- gyro de-skew (gyro_deskew.cpp) ----
constexpr double kMaxGyroRate = 35.0;           // rad/s (> 2000 deg/s: not a rate an OS-1 IMU reports)
constexpr int64_t kGyroKeepUs = 1000000;        // keep ~1 s of samples; time going back > 1 s: new log
constexpr int64_t kGyroEdgeUs = 20000;          // samples must reach within 20 ms of the sweep's ends
constexpr int64_t kGyroMaxGapUs = 50000;        // and have no gap longer than 50 ms
constexpr int64_t kGyroStepUs = 5000;           // integration step (midpoint rule)
constexpr int64_t kMaxSweepUs = 500000;         // a sweep longer than 0.5 s: column times do not make sense
constexpr double kMinDeskewRad = 2e-5;          // rotation over half a sweep below this (0.001 deg): skip
constexpr int64_t kBiasMaxDtUs = 600000;        // consecutive ceilings at most 0.6 s apart for the bias
constexpr double kBiasMaxStep = 0.03;           // rad/s: larger residual rates are a wrong plane
constexpr double kBiasGain = 0.05;              // low-pass gain (a few seconds at 10 Hz)

// ---- attitude / height fallbacks (attitude_height.cpp) ----
constexpr double kImuTiltSigmaRad = 0.5 * kDeg;     // IMU gravity's 1-sigma as attitude source
constexpr double kMinHeldTiltSigmaRad = 0.2 * kDeg; // a held attitude is at least this uncertain
constexpr double kMinHeldZSigmaM = 0.05;            // a held height at least this
constexpr double kHoldGrowth = 2.0;                 // sigma growth per held scan
constexpr double kUnknownZSigmaM = 1e3;             // z unknown
// With a building's area ceilings (attitude_height_areas.cpp):
constexpr size_t kAreaMaxPoints = 3000;             // ceiling inliers looked up per scan (subsampled)
constexpr double kAreaKnownMin = 0.5;               // >= half of them with a height (the building's or learned)
constexpr double kAreaLearnFraction = 0.9;          // learn an area's height from a ceiling >= 90 % in it
constexpr double kAreaFloorGateMinM = 0.01;         // the ceiling's z vs a level floor's: > 3 sigmas and > 1 cm: the floor
constexpr double kPoseMaxAgeS = 1.0;                // a plan pose older than this is not used
constexpr double kPoseMaxExtrapolateS = 0.3;        // extrapolated from the last two poses at most this far
constexpr double kImuTrustNormTolMs2 = 0.4;         // IMU trusted: |mean accel| within this of g
constexpr double kImuTrustSpreadMs2 = 0.6;          // and the samples' rms spread below this
constexpr double kGravityMs2 = 9.80665;
constexpr double kMinBuildingSlope = 1e-3;          // m/m: below this the building's ceiling is flat
constexpr double kOnSlopeDeg = 1.0;                 // tilted this far from the usual level attitude: on a slope
constexpr double kLevelUpGain = 0.05;               // running mean of the level attitude (~20 scans)

// ---- wall selection (wall_select.cpp) ----
constexpr double kPlaneMarginRms = 3.0;        // wall margin at least this many plane rms
constexpr double kHeldPlaneMarginGrowth = 1.5; // margin x this when the plane is last frame's
constexpr double kNoCeilingWallTopM = 2.0;     // no ceiling known yet: wall points up to this above the floor

}  // namespace fploc::seg::k
