// The camera of each map in the map file (version 3): a map whose final BA refined the intrinsics keeps the
// refined camera, beside the nominal one; files of version 2, which have none, give each map its keyframes'.

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

#include "map_test_frames.h"
#include "semslam/core/binary_io.h"
#include "semslam/core/error.h"
#include "semslam/map/map.h"
#include "semslam/map/map_file.h"
#include "support/test_support.h"

namespace semslam {
namespace {

// A camera the final BA could have found for KittiCamera().
PinholeCamera Refined() {
  PinholeCamera c = KittiCamera();
  c.fx = c.fy = 712.8;
  c.cx = 609.5;
  c.cy = 183.9;
  c.distortion.k1 = -0.021;
  c.distortion.k2 = 0.013;
  return c;
}

// Two maps of two keyframes each; map 0's keyframes carry `map0_camera` (its keypoints undistorted with it).
struct TwoMaps {
  Map map;

  explicit TwoMaps(const std::optional<PinholeCamera>& map0_camera) {
    auto lock = map.WriteLock();
    for (std::uint64_t k = 0; k < 4; ++k) {
      if (k == 2) map.StartNewMap();
      KeyFrame* kf = map.AddKeyFrame(MakeFrame(k, 60, /*stereo=*/false, {0, 0, static_cast<double>(k)}));
      if (k < 2 && map0_camera) {
        const FrameData& d = kf->data();
        kf->ReplaceData(MakeFrameData(*map0_camera, std::nullopt, d.features, {}, {}));
      }
      for (int i = 0; i < 10; ++i) {
        MapPoint* p = map.AddMapPoint(Eigen::Vector3d(0.1 * i, 0.0, 10.0 + static_cast<double>(k)), kf);
        p->AddObservation(kf, i);
        kf->SetMapPoint(i, p);
      }
    }
  }
};

std::string Bytes(const std::filesystem::path& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), {}};
}

// The same map as a version-2 file: a version-3 file without its cameras, which is what version 2 wrote.
void RewriteAsVersion2(const std::filesystem::path& v3, const std::filesystem::path& v2) {
  const ChecksummedFile file = ReadChecksummedFile(v3, "SEMSLMAP");
  ASSERT_EQ(file.version, 3u);
  BinaryReader r(file.payload, v3);
  const auto sessions = r.Get<std::uint32_t>();
  for (std::uint32_t i = 0; i < 2 * sessions; ++i) r.GetString();
  r.Get<std::uint32_t>();  // active map
  r.Get<std::uint32_t>();  // next map
  const size_t cameras_at = r.offset();
  const auto cameras = r.Get<std::uint32_t>();
  // Per map: its id, then two cameras of two int32 and nine doubles.
  const size_t cameras_size = 4 + cameras * (4 + 2 * (2 * 4 + 9 * 8));
  std::string payload = file.payload;
  payload.erase(cameras_at, cameras_size);
  WriteChecksummedFile(v2, "SEMSLMAP", 2, payload);
}

TEST(MapFile, EachMapKeepsItsCamera) {
  testing::TempDir dir;
  TwoMaps atlas(Refined());
  MapFileContents contents;
  contents.cameras[0] = {KittiCamera(), Refined()};  // map 1: none given, its keyframes' camera
  const auto path = dir / "map.semslam";
  {
    auto lock = atlas.map.ReadLock();
    WriteMapFile(path, atlas.map, contents);
  }
  Map loaded;
  MapFileContents read;
  {
    auto lock = loaded.WriteLock();
    read = ReadMapFile(path, loaded);
  }
  ASSERT_EQ(read.cameras.size(), 2u);
  EXPECT_TRUE(read.cameras.at(0) == contents.cameras.at(0));
  EXPECT_TRUE(read.cameras.at(0).refined());
  EXPECT_EQ(read.cameras.at(0).camera.distortion.k1, -0.021);
  EXPECT_EQ(read.cameras.at(0).nominal.fx, KittiCamera().fx);
  EXPECT_FALSE(read.cameras.at(1).refined());
  EXPECT_EQ(read.cameras.at(1).camera.fx, KittiCamera().fx);
  EXPECT_TRUE(read.cameras.at(1).camera.distortion.IsZero());
  // The keyframes carry their map's camera (map 0: the refined one's ideal pinhole) and the keypoints they
  // had.
  const auto original = atlas.map.KeyFrames(), kfs = loaded.KeyFrames();
  ASSERT_EQ(kfs.size(), 4u);
  for (size_t k = 0; k < kfs.size(); ++k) {
    EXPECT_EQ(kfs[k]->camera().fx, k < 2 ? 712.8 : KittiCamera().fx) << k;
    EXPECT_TRUE(kfs[k]->camera().distortion.IsZero()) << k;
    ASSERT_EQ(kfs[k]->num_features(), original[k]->num_features());
    for (size_t i = 0; i < kfs[k]->num_features(); ++i)
      EXPECT_EQ(kfs[k]->features().keypoints[i].pixel, original[k]->features().keypoints[i].pixel);
  }
  EXPECT_NE(kfs[0]->features().keypoints[0].pixel,
            MakeFrame(0, 60, false, Eigen::Vector3d::Zero()).features().keypoints[0].pixel)
      << "undistorted with the refined camera";

  // Written again, the same bytes.
  const auto again = dir / "again.semslam";
  {
    auto lock = loaded.ReadLock();
    WriteMapFile(again, loaded, read);
  }
  EXPECT_EQ(Bytes(again), Bytes(path));
}

TEST(MapFile, AVersion2FileGivesEachMapItsKeyFramesCamera) {
  testing::TempDir dir;
  TwoMaps atlas(std::nullopt);
  const auto v3 = dir / "v3.semslam", v2 = dir / "v2.semslam";
  {
    auto lock = atlas.map.ReadLock();
    WriteMapFile(v3, atlas.map);
  }
  RewriteAsVersion2(v3, v2);
  Map loaded;
  MapFileContents read;
  {
    auto lock = loaded.WriteLock();
    read = ReadMapFile(v2, loaded);
  }
  EXPECT_EQ(ReadChecksummedFile(v2, "SEMSLMAP").version, 2u);
  EXPECT_EQ(loaded.NumKeyFrames(), 4u);
  EXPECT_EQ(loaded.NumMapPoints(), 40u);
  EXPECT_EQ(loaded.MapIds(), (std::vector<std::uint32_t>{0, 1}));
  ASSERT_EQ(read.cameras.size(), 2u);
  for (const auto& [map_id, camera] : read.cameras) {
    EXPECT_FALSE(camera.refined()) << map_id;
    EXPECT_EQ(camera.camera.fx, KittiCamera().fx) << map_id;
    EXPECT_EQ(camera.camera.width, KittiCamera().width) << map_id;
  }
  // Saved again (as version 3), it is the file the map makes itself.
  const auto again = dir / "again.semslam";
  {
    auto lock = loaded.ReadLock();
    WriteMapFile(again, loaded, read);
  }
  EXPECT_EQ(Bytes(again), Bytes(v3));
}

TEST(MapFile, ImplausibleMapCamerasAreRefused) {
  testing::TempDir dir;
  const auto expect_refused = [&](const PinholeCamera& camera, const std::string& what) {
    TwoMaps atlas(std::nullopt);
    MapFileContents contents;
    contents.cameras[1] = {KittiCamera(), camera};
    const auto path = dir / "bad.semslam";
    {
      auto lock = atlas.map.ReadLock();
      WriteMapFile(path, atlas.map, contents);
    }
    Map loaded;
    auto lock = loaded.WriteLock();
    try {
      ReadMapFile(path, loaded);
      ADD_FAILURE() << what << " was accepted";
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("camera of map 1"), std::string::npos) << message;
      EXPECT_NE(message.find(what), std::string::npos) << message;
    }
  };
  PinholeCamera c = Refined();
  c.fx = std::nan("");
  expect_refused(c, "intrinsics");
  c = Refined();
  c.distortion.k2 = 50.0;
  expect_refused(c, "distortion");
  c = Refined();
  c.width = 0;
  expect_refused(c, "image size");
  c = Refined();
  c.height = 375;
  expect_refused(c, "different sizes");
}

TEST(KeyFrame, ReplacedDataMustHoldTheSameKeypoints) {
  Map map;
  auto lock = map.WriteLock();
  KeyFrame* kf = map.AddKeyFrame(MakeFrame(0, 60, /*stereo=*/false, {0, 0, 0}));
  EXPECT_THROW(kf->ReplaceData(MakeData(59, 1, false)), InvalidArgument);
  EXPECT_THROW(kf->ReplaceData(nullptr), InvalidArgument);
  kf->ReplaceData(MakeData(60, 1, false));
  EXPECT_EQ(kf->num_features(), 60u);
}

}  // namespace
}  // namespace semslam
