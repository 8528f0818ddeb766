// Map files whose checksum is right but whose content contradicts itself are refused by the loader
// (map/map_validation.h), naming the file and the record.

#include "semslam/map/map_validation.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "semslam/core/binary_io.h"
#include "semslam/core/error.h"
#include "semslam/map/map.h"
#include "semslam/map/map_file.h"
#include "support/kitti_camera.h"
#include "support/test_support.h"

namespace semslam {
namespace {

using ::testing::HasSubstr;

std::shared_ptr<const FrameData> MakeData(int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  FeatureSet features;
  features.pyramid = PyramidGeometry::Make(8, 1.2f);
  features.image_width = 1241;
  features.image_height = 376;
  for (int i = 0; i < n; ++i) {
    Keypoint kp;
    kp.pixel = Eigen::Vector2f(20.0f + static_cast<float>(i) * 30.0f, 100.0f);
    kp.level = 0;
    features.keypoints.push_back(kp);
    features.descriptors.push_back({rng(), rng(), rng(), rng()});
  }
  return MakeFrameData(KittiCamera(), std::nullopt, std::move(features), {}, {});
}

// Three keyframes seeing ten points; `timestamp0` is the first keyframe's time.
struct ThreeKeyFrames {
  Map map;
  std::vector<KeyFrame*> kfs;
  explicit ThreeKeyFrames(double timestamp0 = 0.0) {
    auto lock = map.WriteLock();
    for (std::uint64_t id = 0; id < 3; ++id) {
      Frame frame(id, id == 0 ? timestamp0 : 0.1 * static_cast<double>(id), MakeData(10, id + 1));
      frame.SetPose(Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, -static_cast<double>(id))));
      kfs.push_back(map.AddKeyFrame(frame));
    }
    for (int i = 0; i < 10; ++i) {
      MapPoint* p = map.AddMapPoint(Eigen::Vector3d(0.1 * i, 0.0, 10.0), kfs[0]);
      for (KeyFrame* kf : kfs) {
        p->AddObservation(kf, i);
        kf->SetMapPoint(i, p);
      }
    }
    for (KeyFrame* kf : kfs) kf->UpdateConnections();
  }
};

std::string LoadError(const Map& map, const std::filesystem::path& file) {
  {
    auto lock = map.ReadLock();
    WriteMapFile(file, map);
  }
  Map loaded;
  try {
    auto lock = loaded.WriteLock();
    ReadMapFile(file, loaded);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(MapValidation, ASoundMapLoads) {
  testing::TempDir dir;
  ThreeKeyFrames m;
  EXPECT_EQ(LoadError(m.map, dir / "map.semslam"), "");
}

TEST(MapValidation, ANanTimestampIsRefused) {
  testing::TempDir dir;
  ThreeKeyFrames m(std::numeric_limits<double>::quiet_NaN());
  const std::string error = LoadError(m.map, dir / "map.semslam");
  EXPECT_THAT(error, HasSubstr((dir / "map.semslam").string()));
  EXPECT_THAT(error, HasSubstr("keyframe 0"));
  EXPECT_THAT(error, HasSubstr("timestamp"));
}

// A count is the file's word until its records are read: a point count of 2^64 - 2 in a map with no points
// must end in the file's truncation error, not in an allocation of that many.
TEST(MapValidation, APointCountBeyondTheFileIsRefused) {
  testing::TempDir dir;
  const auto file = dir / "map.semslam";
  {
    Map empty;
    auto lock = empty.ReadLock();
    WriteMapFile(file, empty);
  }
  std::string payload = ReadChecksummedFile(file, "SEMSLMAP").payload;
  // An empty map ends with its keyframe, point and extra-section counts (u64 each), all zero.
  ASSERT_GE(payload.size(), 24u);
  ASSERT_EQ(payload.substr(payload.size() - 24), std::string(24, '\0'));
  payload.replace(payload.size() - 16, 8, std::string("\xfe\xff\xff\xff\xff\xff\xff\xff", 8));
  WriteChecksummedFile(file, "SEMSLMAP", kMapFileVersion, payload);
  Map loaded;
  auto lock = loaded.WriteLock();
  try {
    (void)ReadMapFile(file, loaded);
    ADD_FAILURE() << "a map file claiming 2^64 - 2 points was loaded";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr(file.string()));
  }
}

TEST(MapValidation, TheTreeCannotBeGivenACycle) {
  ThreeKeyFrames m;
  auto lock = m.map.WriteLock();
  m.kfs[1]->ChangeParent(m.kfs[0]);
  m.kfs[2]->ChangeParent(m.kfs[1]);
  m.kfs[0]->ChangeParent(m.kfs[2]);  // would close 0 -> 2 -> 1 -> 0
  m.kfs[1]->ChangeParent(m.kfs[1]);
  EXPECT_EQ(m.kfs[0]->parent(), nullptr);
  EXPECT_EQ(m.kfs[1]->parent(), m.kfs[0]);
  EXPECT_EQ(m.kfs[2]->parent(), m.kfs[1]);
  EXPECT_TRUE(m.kfs[2]->HasAncestor(m.kfs[0]));
  EXPECT_FALSE(m.kfs[0]->HasAncestor(m.kfs[2]));
}

TEST(MapValidation, ARecordCheckFindsEachContradiction) {
  const PinholeCamera camera = KittiCamera();
  std::vector<Keypoint> keypoints(2);
  keypoints[0].pixel = {100.0f, 100.0f};
  keypoints[1].pixel = {200.0f, 50.0f};
  std::vector<float> none;
  KeyFrameRecordCheck record{7, 0.5, &camera, 0.0, camera.width, camera.height, &keypoints, &none, &none,
                             std::nullopt, 1.0};
  EXPECT_NO_THROW(CheckKeyFrameRecord(record, "map.semslam"));
  const auto error = [&](KeyFrameRecordCheck broken) -> std::string {
    try {
      CheckKeyFrameRecord(broken, "map.semslam");
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  std::vector<Keypoint> far = keypoints;
  far[1].pixel = {1e30f, 50.0f};
  KeyFrameRecordCheck far_record = record;
  far_record.keypoints = &far;
  EXPECT_THAT(error(far_record), HasSubstr("keypoint 1"));
  KeyFrameRecordCheck wrong_size = record;
  wrong_size.image_width = 640;
  EXPECT_THAT(error(wrong_size), HasSubstr("640"));
  PinholeCamera tiny = camera;
  tiny.fx = 0.0;
  KeyFrameRecordCheck bad_camera = record;
  bad_camera.camera = &tiny;
  EXPECT_THAT(error(bad_camera), HasSubstr("intrinsics"));
  KeyFrameRecordCheck bad_gps = record;
  bad_gps.gps_enu = Eigen::Vector3d(std::numeric_limits<double>::infinity(), 0, 0);
  EXPECT_THAT(error(bad_gps), HasSubstr("GPS"));
  EXPECT_THROW(CheckPointRecord(3, Eigen::Vector3d(0, 0, 1e30), 1, 1, "map.semslam"), InputError);
  EXPECT_THROW(CheckPointRecord(3, Eigen::Vector3d(0, 0, 10), -1, 0, "map.semslam"), InputError);
  EXPECT_NO_THROW(CheckPointRecord(3, Eigen::Vector3d(0, 0, 10), 3, 2, "map.semslam"));
}

TEST(MapValidation, AMissingParentIsRefusedAndACycleIsCutAboveItsOldestKeyFrame) {
  std::unordered_map<std::uint64_t, std::uint64_t> tree = {{0, kNoParent}, {1, 0}, {2, 1}};
  EXPECT_TRUE(RepairSpanningTree(tree, "m").empty());
  EXPECT_EQ(tree.at(2), 1u);
  std::unordered_map<std::uint64_t, std::uint64_t> missing = {{0, kNoParent}, {1, 5}};
  EXPECT_THROW(RepairSpanningTree(missing, "m"), InputError);
  // What semslam wrote before 2026-11-28 after a loss: map 1's first keyframe (4) under its child (5).
  std::unordered_map<std::uint64_t, std::uint64_t> atlas = {{0, kNoParent}, {1, 0}, {4, 5}, {5, 4}, {6, 5}};
  EXPECT_EQ(RepairSpanningTree(atlas, "m"), std::vector<std::uint64_t>{4});
  EXPECT_EQ(atlas.at(4), kNoParent);
  EXPECT_EQ(atlas.at(5), 4u);
  EXPECT_EQ(atlas.at(6), 5u);
  std::unordered_map<std::uint64_t, std::uint64_t> self = {{0, 0}, {1, 0}};
  EXPECT_EQ(RepairSpanningTree(self, "m"), std::vector<std::uint64_t>{0});
  EXPECT_EQ(self.at(0), kNoParent);
}

}  // namespace
}  // namespace semslam
