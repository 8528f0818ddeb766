#pragma once
// Bridges between the map and the optimizers: bundle-adjustment problems built from keyframes and map
// points, and global BA applied to the map (the Sim(3) refinement of a loop: sim3_refinement.h).

#include <atomic>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "semslam/map/map.h"
#include "semslam/optim/bundle_adjustment.h"

namespace semslam {

// One entry per problem observation: which keyframe saw which point.
struct ObservationRef {
  KeyFrame* keyframe = nullptr;
  MapPoint* point = nullptr;
};

// Adds poses for `keyframes` (free) and `fixed_keyframes` (fixed; a map's origin is always fixed), the
// `points`, and every observation of those points by those keyframes. Read lock.
void BuildBundleAdjustmentProblem(const std::vector<KeyFrame*>& keyframes,
                                  const std::vector<KeyFrame*>& fixed_keyframes,
                                  const std::vector<MapPoint*>& points, BundleAdjustmentProblem* problem,
                                  std::vector<ObservationRef>* refs);

// Removes each observation from its keyframe and its point, and the points left with too few observations
// from the map; observations the map no longer holds (a keyframe or point turned bad, a point replaced) are
// skipped. Write lock.
void DropObservations(Map& map, const std::vector<ObservationRef>& observations);

// Writes optimized poses and points back (skipping bad ones) and drops outlier observations. Write lock.
void ApplyBundleAdjustment(Map& map, const BundleAdjustmentProblem& problem,
                           const BundleAdjustmentResult& result, const std::vector<KeyFrame*>& keyframes,
                           const std::vector<MapPoint*>& points, const std::vector<ObservationRef>& refs,
                           bool drop_outliers);

// A global BA of bounded memory. The solver's working memory is about as large as the map itself, so a map of
// more than `window_keyframes` keyframes is adjusted in a sweep of consecutive windows of its keyframes (by
// id, that is along the drive), each with the points its keyframes observe, and the other keyframes observing
// them held still (at the poses earlier windows gave them). It refines the map locally and keeps the shape
// the loop correction gave it at large; a map within one window gets the plain global BA.
// (GlobalBundleAdjustment gives a larger map its large-scale shape first, from a spread of its keyframes.)
//
// The Huber kernel only bounds each wrong match's pull, and many of them still bend a map: after the first
// pass, the observations failing the chi-square test are left out of a second pass of as many iterations and
// dropped from the map (`drop_outliers`). With them kept, a monocular map's final BA left a stretch of the
// synthetic city 0.6 % off in scale (seed 1 lost for 2 s at frame 700: 0.176 m ATE, against 0.092 m with them
// left out of the final BA's second pass, from the same tracking).
struct GlobalBundleAdjustmentOptions {
  int iterations = 10;
  // The second pass's: it starts where the first stopped, which after a merge moved whole maps onto each
  // other may still be far from its minimum.
  int refine_iterations = 10;
  int window_keyframes = 1000;
  bool drop_outliers = true;
  // Monocular: each keyframe follows the stretch the BA gives the map around it (LocalScaleChanges), so that
  // the frames kept relative to it stretch too.
  bool follow_local_scale = false;
  // Set (from another thread) to stop after the current solver iteration; no later window starts.
  std::atomic<bool>* abort = nullptr;

  void Check() const;  // throws InvalidArgument
};

// What a global BA found, not yet written into the map: the keyframes it moved, the points, and the
// observations that failed the chi-square test (GlobalBundleAdjustmentOptions::drop_outliers).
struct GlobalBundleAdjustmentResult {
  std::uint32_t map_id = 0;
  std::unordered_map<KeyFrame*, Rigid3d> camera_from_world;
  std::unordered_map<MapPoint*, Eigen::Vector3d> positions;
  std::vector<ObservationRef> outliers;
  int windows = 0;
  bool aborted = false;
};

// [begin, end) of each window over `num_keyframes` keyframes: the fewest windows of at most
// `window_keyframes`, of near-equal sizes.
std::vector<std::pair<size_t, size_t>> GlobalBundleAdjustmentWindows(size_t num_keyframes,
                                                                     int window_keyframes);

// Runs the global BA of one map of the atlas. With `lock_map`, each window is read under the map's read lock
// and solved without it (the map may change meanwhile: keyframes and points that turn bad are skipped);
// without, the caller holds a lock.
GlobalBundleAdjustmentResult AdjustMapInWindows(const Map& map, std::uint32_t map_id,
                                                const GlobalBundleAdjustmentOptions& options, bool lock_map);

// How LocalScaleChanges tells the stretch around a keyframe.
struct LocalScaleOptions {
  // Keyframes with fewer points the BA also moved are left out.
  int min_points = 20;
  // A step between keyframes shorter than this fraction of the keyframe's median depth is too short to tell
  // the stretch (a car at a stop).
  double min_spacing_of_depth = 0.02;
  // A step's stretch further than this factor from the points' depth ratio is not a stretch but a keyframe
  // the BA moved (at a merge's seam, after a loop).
  double max_spacing_disagreement = 1.15;

  void Check() const;  // throws InvalidArgument
};

// How much a monocular BA stretches the map around each keyframe it moves ("before" is the map as it is: call
// it before writing the result). A frame's pose is kept relative to a keyframe in the units of the map there
// when it was tracked (KeyFrame::scale_correction); a BA that undid part of a merge's stretch along a young
// map left its frames 3-4 % long between keyframes, its first 20 frames 0.3 m behind.
//
// The stretch is that of the step to the next keyframe along the drive (the step before it for the last),
// which is what the frames tracked from the keyframe span. Where that step is too short or disagrees with the
// points, it is the median, over the keyframe's points the BA also moved, of their depth after over their
// depth before. The depth ratio alone left a sawtooth after some merges (the spread of the frame-step ratios
// over a young map's first 30 frames 0.058 in one run, 0.011-0.015 with the steps'): the points' depths do
// not stretch exactly as the steps between keyframes do.
std::unordered_map<KeyFrame*, double> LocalScaleChanges(const GlobalBundleAdjustmentResult& result,
                                                        const LocalScaleOptions& options = {});

// The same for a solved problem of BuildBundleAdjustmentProblem (which holds the solution after the solve),
// over its `keyframes` (poses in the problem's order, fixed ones included) and `points`.
std::unordered_map<KeyFrame*, double> LocalScaleChanges(const BundleAdjustmentProblem& solved,
                                                        const std::vector<KeyFrame*>& keyframes,
                                                        const std::vector<MapPoint*>& points,
                                                        const LocalScaleOptions& options = {});

// KeyFrame::CorrectScale by each change. Write lock.
void FollowLocalScaleChanges(const std::unordered_map<KeyFrame*, double>& changes);

// Writes the result into its map as the map is now (skipping what turned bad), drops its outlier observations
// and updates the points' normals. Keyframes made since the BA read the map follow their nearest ancestor in
// the result down the spanning tree; points the result does not hold follow their reference keyframe. With
// `follow_local_scale` (monocular), the keyframes follow LocalScaleChanges first, and those made since
// stretch with their ancestor: moved rigidly, the newest part of a map kept its old units beside a stretched
// neighbourhood. Returns how many keyframes followed an ancestor. Write lock.
int WriteGlobalBundleAdjustment(Map& map, const GlobalBundleAdjustmentResult& result,
                                bool follow_local_scale = false);

// Optimizes every keyframe and point of one map of the atlas in place. A map larger than one window is first
// adjusted on a spread of its keyframes that fits one (every k-th, with the points two of them observe; the
// keyframes between follow them), then in windows, which alone would keep the large-scale shape it has. Write
// lock held by the caller.
void GlobalBundleAdjustment(Map& map, std::uint32_t map_id, const GlobalBundleAdjustmentOptions& options);

// What the self-calibrating global BA of one map did.
struct IntrinsicsRefinement {
  std::uint32_t map_id = 0;
  bool accepted = false;  // the map keeps the poses and points of the refined camera, and the camera
  std::string reason;     // why not, when not accepted
  PinholeCamera nominal;  // the camera the map's keyframes carried
  PinholeCamera refined;  // with the radial terms k1, k2 on the keyframes' keypoints
  // BundleAdjustmentResult::final_capped_chi2 of the plain BA, and of the refinement that followed it.
  double plain_cost = 0.0, refined_cost = 0.0;
};

// When the final BA of a monocular map may also refine the intrinsics.
struct SelfCalibrationOptions {
  // The refinement must lower the robust cost by this share of it to be kept.
  double min_cost_reduction = 0.01;
  // Fewer keyframes see too little of the image from too few places to tell the camera from the trajectory: a
  // short map bent by a poor start found a camera 4 % off in focal length and 33 px off in principal point.
  int min_keyframes = 15;
  // Plausibility: a camera further from the nominal one is a trajectory the images could not pin down, not a
  // calibration. The focal length within this share of the nominal one, the principal point within this share
  // of the image's width (cx) and height (cy), and |k1|, |k2| at most max_radial.
  double max_focal_change = 0.10;
  double max_principal_point_shift = 0.05;
  double max_radial = 0.2;
  void Check() const;
};

// The global BA of a monocular map, then one that also refines the intrinsics
// (BundleAdjustmentOptions::refine_intrinsics) from its result. The map keeps the refinement only when it
// earns its five parameters, lowering the robust cost by at least `min_cost_reduction` of it, and is
// plausible (SelfCalibrationOptions). Otherwise, and for a map with stereo observations, it keeps the plain
// BA's result. A refinement kept becomes the map's camera: besides the poses and points fitted to it, the
// keyframes take it (ExpressKeyFramesInCamera), so that whatever reads the map after (semantics, the map
// file, tracking against it later) sees the camera the map was fitted to. The radial terms apply to the
// keypoints as the keyframes hold them, which are raw pixels only when the map was tracked with an
// undistorted camera (the caller's concern: see SlamSystem::Finish). The intrinsics are shared by the whole
// map: a map larger than one window (GlobalBundleAdjustmentOptions) gets the windowed plain BA, the camera is
// told from a spread of its keyframes that fits one window (every k-th, with the points two of them observe,
// solved plain and refined), and when kept the map takes it and is adjusted in windows again. Write lock held
// by the caller.
IntrinsicsRefinement SelfCalibratingGlobalBundleAdjustment(Map& map, std::uint32_t map_id,
                                                           const GlobalBundleAdjustmentOptions& options,
                                                           const SelfCalibrationOptions& calibration);

// Gives every keyframe of one map `camera`: their keypoints, pixels of the camera they carry, are taken as
// pixels of `camera` and undistorted with it (MakeFrameData); each keyframe then carries its ideal pinhole.
// Write lock.
void ExpressKeyFramesInCamera(Map& map, std::uint32_t map_id, const PinholeCamera& camera);

}  // namespace semslam
