// Drives of one merged map welded along the street they share (mapping/session_welding.h): each drive arrives
// with its own points for the same facades; where two drives' keyframes stand at one place with one heading,
// their points become one. A drive whose map is not where the others are keeps its own.

#include "semslam/mapping/session_welding.h"

#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>
#include <vector>

#include "semslam/core/error.h"
#include "support/kitti_camera.h"

namespace semslam {
namespace {

struct WorldPoint {
  Eigen::Vector3d position;
  Descriptor descriptor;
};

// Facades on both sides of a street along +z, seen by cameras looking down it.
std::vector<WorldPoint> Street(std::uint32_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<WorldPoint> points;
  for (int i = 0; i < 300; ++i) {
    const double side = i % 2 == 0 ? -6.0 : 6.0;
    points.push_back({Eigen::Vector3d(side, -3.0 + 4.0 * unit(rng), 8.0 + 40.0 * unit(rng)),
                      Descriptor{rng(), rng(), rng(), rng()}});
  }
  return points;
}

class ThreeDrives : public ::testing::Test {
 protected:
  // A drive of the current session: keyframes at `centers` looking along +z, its own point for every world
  // point it sees. `offset` moves the whole drive (keyframes and points) away from where it was.
  void AddDrive(const std::vector<Eigen::Vector3d>& centers, const Eigen::Vector3d& offset) {
    const PinholeCamera camera = KittiCamera();
    std::map<size_t, MapPoint*> own;
    for (const Eigen::Vector3d& center : centers) {
      FeatureSet features;
      features.pyramid = PyramidGeometry::Make(8, 1.2f);
      features.image_width = camera.width;
      features.image_height = camera.height;
      std::vector<size_t> seen;
      for (size_t j = 0; j < street_.size(); ++j) {
        const Eigen::Vector3d in_camera = street_[j].position - center;
        if (in_camera.z() <= 1.0) continue;
        const Eigen::Vector2d pixel = camera.Project(in_camera);
        if (!camera.InImage(pixel)) continue;
        Keypoint kp;
        kp.pixel = pixel.cast<float>();
        features.keypoints.push_back(kp);
        features.descriptors.push_back(street_[j].descriptor);
        seen.push_back(j);
      }
      Frame frame(next_id_, 0.1 * static_cast<double>(next_id_),
                  MakeFrameData(camera, std::nullopt, std::move(features), {}, {}));
      ++next_id_;
      frame.SetPose(Rigid3d(Eigen::Quaterniond::Identity(), -(center + offset)));
      KeyFrame* kf = map_.AddKeyFrame(frame);
      for (size_t slot = 0; slot < seen.size(); ++slot) {
        MapPoint*& p = own[seen[slot]];
        if (p == nullptr) p = map_.AddMapPoint(street_[seen[slot]].position + offset, kf);
        kf->SetMapPoint(static_cast<int>(slot), p);
        p->AddObservation(kf, static_cast<int>(slot));
      }
    }
    for (const auto& [j, p] : own) {
      p->UpdateDescriptor();
      p->UpdateNormalAndDepth();
    }
  }

  static std::vector<Eigen::Vector3d> Along(double x, double first_z) {
    std::vector<Eigen::Vector3d> centers;
    for (int i = 0; i < 6; ++i) centers.emplace_back(x, 0.0, first_z + 2.0 * i);
    return centers;
  }

  // How many good points are seen by keyframes of both sessions a and b.
  size_t Shared(std::uint32_t a, std::uint32_t b) {
    size_t shared = 0;
    for (MapPoint* p : map_.MapPointsOfMap(0)) {
      if (p->is_bad()) continue;
      std::set<std::uint32_t> sessions;
      for (const auto& [kf, index] : p->observations()) sessions.insert(kf->session());
      shared += sessions.count(a) && sessions.count(b);
    }
    return shared;
  }

  Map map_;
  std::vector<WorldPoint> street_ = Street(7);
  std::uint64_t next_id_ = 0;
};

TEST_F(ThreeDrives, DrivesWhereEachOtherIsShareTheirPointsAndAMisplacedOneKeepsItsOwn) {
  auto lock = map_.WriteLock();
  AddDrive(Along(0.0, 0.0), Eigen::Vector3d::Zero());
  map_.BeginSession("second", "");
  AddDrive(Along(0.4, 1.0), Eigen::Vector3d::Zero());  // the next lane, where its map says it is
  map_.BeginSession("third", "");
  AddDrive(Along(0.4, 1.0), Eigen::Vector3d(1.5, 0.0, 0.0));  // its map 1.5 m off to the side
  const size_t points_before = map_.NumMapPoints();
  ASSERT_EQ(Shared(0, 1), 0u);

  const SessionWeldingSummary welded = WeldSessions(map_, 0);
  EXPECT_EQ(welded.keyframes, 18u);  // each has neighbours of both other drives within 3 spacings
  // The first two drives' points of one world point became one: measured 292 of the street's 300.
  EXPECT_GE(Shared(0, 1), 280u);
  EXPECT_EQ(map_.NumMapPoints(), points_before - Shared(0, 1));
  // The misplaced drive's points project a metre and more from the keypoints of the others: none fused.
  EXPECT_EQ(Shared(0, 2), 0u);
  EXPECT_EQ(Shared(1, 2), 0u);
  // The keyframes of the first two drives are now covisible.
  KeyFrame* first = map_.KeyFramesOfMap(0).front();
  bool covisible_with_second = false;
  for (KeyFrame* kf : first->Covisibles()) covisible_with_second |= kf->session() == 1;
  EXPECT_TRUE(covisible_with_second);
}

TEST_F(ThreeDrives, ADriveFacingTheOtherWayIsNotItsNeighbour) {
  auto lock = map_.WriteLock();
  AddDrive(Along(0.0, 0.0), Eigen::Vector3d::Zero());
  map_.BeginSession("second", "");
  AddDrive(Along(0.4, 1.0), Eigen::Vector3d::Zero());
  SessionWeldingOptions options;
  options.max_heading_difference_deg = 30.0;
  // The second drive turned 31 degrees, one past the limit: beside the first, but not its neighbour.
  for (KeyFrame* kf : map_.KeyFramesOfMap(0)) {
    if (kf->session() != 1) continue;
    const Eigen::Quaterniond turned(Eigen::AngleAxisd(31.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()));
    kf->SetPose(Rigid3d(turned.inverse(), -(turned.inverse() * kf->center())));
  }
  EXPECT_EQ(WeldSessions(map_, 0, options).keyframes, 0u);
  EXPECT_EQ(Shared(0, 1), 0u);
}

TEST(SessionWeldingOptions, CheckRefusesNonsense) {
  SessionWeldingOptions options;
  EXPECT_NO_THROW(options.Check());
  options.neighbour_radius_spacings = 0.0;
  EXPECT_THROW(options.Check(), InvalidArgument);
  options = {};
  options.max_heading_difference_deg = 200.0;
  EXPECT_THROW(options.Check(), InvalidArgument);
  options = {};
  options.max_neighbours = 0;
  EXPECT_THROW(options.Check(), InvalidArgument);
}

}  // namespace
}  // namespace semslam
