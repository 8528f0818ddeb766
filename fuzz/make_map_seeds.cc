// Writes the seed corpus of fuzz_map_file: the payloads of two small maps (monocular and stereo, three
// keyframes, a dozen points), as WriteMapFile writes them. Run it again when the map file format changes:
//   build/asan/fuzz/make_map_seeds fuzz/corpus/map_file
#include <cstdio>
#include <fstream>
#include <random>
#include <string>

#include "semslam/core/binary_io.h"
#include "semslam/map/map.h"
#include "semslam/map/map_file.h"

namespace semslam {
namespace {

PinholeCamera Camera() {
  PinholeCamera camera;
  camera.width = 1241;
  camera.height = 376;
  camera.fx = camera.fy = 718.856;
  camera.cx = 607.1928;
  camera.cy = 185.2157;
  return camera;
}

std::shared_ptr<const FrameData> MakeData(int n, std::uint64_t seed, bool stereo) {
  std::mt19937_64 rng(seed);
  FeatureSet features;
  features.pyramid = PyramidGeometry::Make(8, 1.2f);
  features.image_width = 1241;
  features.image_height = 376;
  std::vector<float> right_u, depth;
  for (int i = 0; i < n; ++i) {
    Keypoint kp;
    kp.pixel = Eigen::Vector2f(40.0f + static_cast<float>(i) * 50.0f, 100.0f + static_cast<float>(i % 3) * 40.0f);
    kp.angle_deg = static_cast<float>(rng() % 360);
    kp.response = static_cast<float>(rng() % 100);
    kp.level = static_cast<int>(rng() % 8);
    features.keypoints.push_back(kp);
    features.descriptors.push_back({rng(), rng(), rng(), rng()});
    if (stereo) {
      depth.push_back(5.0f + static_cast<float>(i % 7));
      right_u.push_back(kp.pixel.x() - 20.0f);
    }
  }
  std::optional<StereoRig> rig;
  if (stereo) rig = StereoRig{Camera(), 0.54};
  return MakeFrameData(Camera(), rig, std::move(features), std::move(right_u), std::move(depth));
}

void WriteSeed(const std::filesystem::path& dir, const std::string& name, bool stereo) {
  Map map;
  {
    auto lock = map.WriteLock();
    std::vector<KeyFrame*> keyframes;
    for (std::uint64_t id = 0; id < 3; ++id) {
      Frame frame(id, 0.1 * static_cast<double>(id), MakeData(12, id + 7, stereo));
      frame.SetPose(Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, -static_cast<double>(id))));
      keyframes.push_back(map.AddKeyFrame(frame));
    }
    for (int i = 0; i < 12; ++i) {
      MapPoint* p = map.AddMapPoint(Eigen::Vector3d(0.1 * i, 0.05 * i, 10.0 + i), keyframes[0]);
      for (KeyFrame* kf : keyframes) {
        p->AddObservation(kf, i);
        kf->SetMapPoint(i, p);
      }
      p->UpdateDescriptor();
      p->UpdateNormalAndDepth();
    }
    for (KeyFrame* kf : keyframes) kf->UpdateConnections();
  }
  const std::filesystem::path file = dir / (name + ".semslam");
  {
    auto lock = map.ReadLock();
    WriteMapFile(file, map, {{{"geo", R"({"note": "an opaque extra section"})"}}});
  }
  // The fuzz target adds the header itself: keep the payload only.
  const ChecksummedFile contents = ReadChecksummedFile(file, std::string_view("SEMSLMAP", 8));
  std::filesystem::remove(file);
  std::ofstream(dir / (name + ".bin"), std::ios::binary) << contents.payload;
  std::printf("%s: %zu bytes\n", (dir / (name + ".bin")).c_str(), contents.payload.size());
}

}  // namespace
}  // namespace semslam

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_map_seeds DIR\n");
    return 2;
  }
  std::filesystem::create_directories(argv[1]);
  semslam::WriteSeed(argv[1], "mono", false);
  semslam::WriteSeed(argv[1], "stereo", true);
  return 0;
}
