#pragma once
// Landmarks in the SLAM map (paper §III-D.1): catalogue positions transformed into the map frame, each
// associated with its nearest keyframe, and the fuzzy membership field m(x, y) = G(x, y; x_l, y_l, sigma).
//
// Membership. G is the 2D isotropic Gaussian in the horizontal (ENU east-north) plane, in metres, so sigma
// means the same on any map scale. Two values are reported:
//  - `membership` (normalized): exp(-d^2 / (2 sigma^2)), 1 at the landmark. This is the fuzzy membership
//    degree used wherever a number is compared or shown: landmarks.geojson's "membership", nearest-landmark
//    lists of localization, the raster plot.
//  - `membership_pdf`: exp(-d^2 / (2 sigma^2)) / (2 pi sigma^2), the paper's PDF value, in 1/m^2; it
//  integrates to
//    1 over the plane, so it is the one to use as a likelihood (e.g. weighing candidate places), and it is
//    written next to the normalized value.

#include <limits>
#include <optional>
#include <vector>

#include "semslam/geo/frame_position.h"
#include "semslam/geo/georeference.h"
#include "semslam/landmarks/catalogue.h"

namespace semslam {

struct Membership {
  double value = 0.0;  // normalized, in [0, 1]
  double pdf = 0.0;    // Gaussian density, 1/m^2
};

// Membership at horizontal distance `distance_m` from a landmark.
Membership GaussianMembership(double distance_m, double sigma_m);
// Between horizontal positions (metres; ENU x, y).
Membership GaussianMembership(const Eigen::Vector2d& position, const Eigen::Vector2d& landmark,
                              double sigma_m);

struct LandmarkOptions {
  double sigma_m = 25.0;  // membership standard deviation
  // Landmarks farther than this (horizontal) from every keyframe are kept but not associated
  // (nearest_keyframe = -1); infinity: always associate.
  double max_association_distance_m = std::numeric_limits<double>::infinity();

  void Check() const;
};

struct PlacedLandmark {
  Landmark landmark;
  Eigen::Vector3d enu = Eigen::Vector3d::Zero();           // ENU metres; a catalogue entry without altitude
                                                           // gets its nearest keyframe's ENU altitude
  Eigen::Vector3d map_position = Eigen::Vector3d::Zero();  // SLAM map frame
  int nearest_keyframe = -1;                               // index into the keyframes given; -1: none
  double keyframe_distance_m = 0.0;                        // horizontal, metres
  Membership keyframe_membership;                          // of that keyframe
};

// Transforms the catalogue into the map and associates each landmark with its nearest keyframe (horizontal
// ENU distance); the map position goes through that keyframe's place (Georeference::EnuToMapAt). `keyframes`
// may be empty (no association).
std::vector<PlacedLandmark> PlaceLandmarks(const std::vector<Landmark>& catalogue,
                                           const Georeference& georeference, const FramePositions& keyframes,
                                           const LandmarkOptions& options = {});

// memberships[k][l]: keyframe k's membership to landmark l.
std::vector<std::vector<Membership>> KeyframeMemberships(const FramePositions& keyframes,
                                                         const std::vector<PlacedLandmark>& landmarks,
                                                         const Georeference& georeference, double sigma_m);

struct NearLandmark {
  int landmark = -1;  // index into the landmarks given
  double distance_m = 0.0;
  Membership membership;
};
// The landmarks nearest a map position (horizontal ENU distance), nearest first, at most `max_count`.
std::vector<NearLandmark> NearestLandmarks(const Eigen::Vector3d& map_position,
                                           const std::vector<PlacedLandmark>& landmarks,
                                           const Georeference& georeference, double sigma_m,
                                           size_t max_count = 3);

// The membership field on a grid in the ENU plane: cell (col, row) is centred at
// origin + ((col + 0.5) * cell_m, (row + 0.5) * cell_m); row 0 is the southernmost.
struct MembershipRaster {
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  // ENU south-west corner, metres
  double cell_m = 1.0;
  int cols = 0, rows = 0;
  std::vector<float> max_membership;  // max over landmarks of the normalized membership, row-major
  std::vector<int> best_landmark;     // argmax (-1 where every membership is below 1e-6)
  std::vector<float> sum_pdf;         // sum over landmarks of the PDF values, 1/m^2

  Eigen::Vector2d CellCentre(int col, int row) const {
    return origin + Eigen::Vector2d((col + 0.5) * cell_m, (row + 0.5) * cell_m);
  }
};

// Over the given ENU rectangle [min, max]; the cell size grows if needed to keep at most max_cells cells.
MembershipRaster RasterizeMembership(const std::vector<PlacedLandmark>& landmarks,
                                     const Eigen::Vector2d& enu_min, const Eigen::Vector2d& enu_max,
                                     double cell_m, double sigma_m, size_t max_cells = 4'000'000);

// landmarks.geojson: a FeatureCollection of Points (WGS84 [lon, lat, alt]) with properties name, category,
// map_xyz, enu, nearest keyframe (index, keyframe id, frame index), its distance, membership and
// membership_pdf, and sigma_m.
void WriteLandmarksGeoJson(const std::filesystem::path& path, const std::vector<PlacedLandmark>& landmarks,
                           const FramePositions& keyframes, double sigma_m);

// Placed landmarks as compact JSON (for the map file's extra sections) and back; the parser throws InputError
// naming `source` and the field.
std::string PlacedLandmarksToJson(const std::vector<PlacedLandmark>& landmarks);
std::vector<PlacedLandmark> PlacedLandmarksFromJson(const std::string& text,
                                                    const std::filesystem::path& source);

}  // namespace semslam
