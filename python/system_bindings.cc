// semslam.open_sequence and semslam.System: feed frames to SLAM from Python.

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <string>

#include "bindings.h"
#include "semslam/io/sequence.h"
#include "semslam/io/trajectory_io.h"
#include "semslam/semantics/segmenter.h"
#include "semslam/system/slam_config.h"
#include "semslam/system/slam_system.h"

namespace semslam::python {

namespace {

py::dict SequenceCameraDict(const PinholeCamera& camera, const std::optional<StereoRig>& stereo) {
  py::dict d = CameraDict(camera);
  if (stereo) d["baseline"] = stereo->baseline;
  return d;
}

PinholeCamera CameraFromDict(const py::dict& d) {
  PinholeCamera camera;
  try {
    camera.width = d["width"].cast<int>();
    camera.height = d["height"].cast<int>();
    camera.fx = d["fx"].cast<double>();
    camera.fy = d["fy"].cast<double>();
    camera.cx = d["cx"].cast<double>();
    camera.cy = d["cy"].cast<double>();
  } catch (const std::exception&) {
    // A key missing (error_already_set) or a value of another type (cast_error).
    throw py::value_error(
        "camera: a dict with width, height (integers), fx, fy, cx, cy (numbers) and baseline for stereo");
  }
  camera.Check();
  return camera;
}

std::optional<StereoRig> RigFromDict(const py::dict& d, const PinholeCamera& camera, SensorMode mode) {
  if (!d.contains("baseline")) {
    if (mode == SensorMode::kStereo) throw py::value_error("camera: stereo needs 'baseline' (metres)");
    return std::nullopt;
  }
  StereoRig rig{camera, 0.0};
  try {
    rig.baseline = d["baseline"].cast<double>();
  } catch (const py::cast_error&) {
    throw py::value_error("camera: 'baseline' must be a number (metres)");
  }
  rig.Check();
  return rig;
}

py::array_t<std::uint8_t> ImageArray(const cv::Mat& image) {
  cv::Mat grey = image.isContinuous() ? image : image.clone();
  py::array_t<std::uint8_t> out({grey.rows, grey.cols});
  std::memcpy(out.mutable_data(), grey.data, static_cast<size_t>(grey.rows) * static_cast<size_t>(grey.cols));
  return out;
}

// A grey uint8 image (H x W) from NumPy, copied (tracking keeps images for later segmentation).
cv::Mat MatFromArray(const py::array& array) {
  if (array.size() == 0) return {};
  const auto image = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>::ensure(array);
  if (!image || image.ndim() != 2) throw py::value_error("image: a 2-D uint8 (grey) array");
  return cv::Mat(static_cast<int>(image.shape(0)), static_cast<int>(image.shape(1)), CV_8UC1,
                 const_cast<std::uint8_t*>(image.data()))
      .clone();
}

class Sequence {
 public:
  explicit Sequence(const std::filesystem::path& path) : sequence_(OpenSequence(path)) {}
  size_t size() const { return sequence_->size(); }
  double Timestamp(size_t i) const {
    Check(i);
    return sequence_->Timestamp(i);
  }
  py::array_t<std::uint8_t> Image(size_t i, int camera) const {
    Check(i);
    return ImageArray(sequence_->LoadImage(i, camera));
  }
  py::dict Camera() const { return SequenceCameraDict(sequence_->camera(), sequence_->stereo()); }
  std::string Name() const { return sequence_->name(); }
  py::object GroundTruth() const {
    const auto truth = sequence_->GroundTruth();
    if (!truth) return py::none();
    std::vector<Rigid3d> poses;
    py::array_t<double> stamps(static_cast<py::ssize_t>(truth->size()));
    auto s = stamps.mutable_unchecked<1>();
    for (size_t i = 0; i < truth->size(); ++i) {
      s(static_cast<py::ssize_t>(i)) = (*truth)[i].timestamp;
      poses.push_back((*truth)[i].world_from_camera);
    }
    return py::make_tuple(stamps, PosesArray(poses));
  }

 private:
  void Check(size_t i) const {
    if (i >= sequence_->size())
      throw py::index_error("frame " + std::to_string(i) + " is outside the sequence");
  }
  std::unique_ptr<ImageSequence> sequence_;
};

class PySystem {
 public:
  PySystem(const py::dict& camera, const std::string& mode, const std::string& pacing,
           std::optional<std::filesystem::path> config, std::optional<std::filesystem::path> vocabulary,
           const std::string& segmenter, std::optional<std::filesystem::path> labels) {
    SlamOptions options;
    const auto sensor = ParseSensorMode(mode);
    const auto parsed_pacing = ParsePacing(pacing);
    if (!sensor) throw py::value_error("mode: 'mono' or 'stereo'");
    if (!parsed_pacing) throw py::value_error("pacing: 'fast', 'realtime' or 'synchronous'");
    options.mode = *sensor;
    if (config) ApplySlamConfig(*config, &options);
    options.pacing = *parsed_pacing;
    if (vocabulary) options.vocabulary = *vocabulary;
    camera_ = CameraFromDict(camera);
    stereo_ = options.mode == SensorMode::kStereo;
    system_ = std::make_unique<SlamSystem>(options, camera_, RigFromDict(camera, camera_, options.mode));
    if (segmenter != "none") {
      SegmenterContext context;
      if (labels) context.truth_label_dir = *labels;
      system_->EnableSegmentation(MakeSegmenter(segmenter, context));
    }
  }

  py::dict Process(const py::array& image, double timestamp, const py::object& right) {
    const cv::Mat left = MatFromArray(image);
    CheckImageSize(left, "image");
    cv::Mat right_image;
    if (stereo_) {
      if (right.is_none())
        throw py::value_error("right: a stereo system needs the right image of each frame");
      right_image = MatFromArray(right.cast<py::array>());
      CheckImageSize(right_image, "right");
    } else if (!right.is_none()) {
      throw py::value_error("right: a monocular system takes no right image (mode='stereo' does)");
    }
    TrackingResult result;
    {
      py::gil_scoped_release release;  // tracking takes a while; the mapping threads never need Python
      // Under the lock, two threads feeding one system still give increasing times (SlamSystem checks them).
      const std::lock_guard<std::mutex> lock(mutex_);
      result = system_->ProcessFrame(next_frame_, timestamp, left, right_image);
      ++next_frame_;
    }
    py::dict d;
    d["state"] = std::string(ToString(result.state));
    d["pose"] =
        result.camera_from_world ? py::object(PoseArray(result.camera_from_world->Inverse())) : py::none();
    d["matched"] = result.matched_points;
    d["new_keyframe"] = result.new_keyframe;
    d["initialized"] = result.initialized_now;
    d["relocalized"] = result.relocalized;
    d["milliseconds"] = result.milliseconds;
    return d;
  }

  void Finish() {
    py::gil_scoped_release release;
    const std::lock_guard<std::mutex> lock(mutex_);
    system_->Finish();
  }

  py::tuple Trajectory() const {
    std::vector<Rigid3d> poses;
    std::vector<double> stamps;
    semslam::Trajectory trajectory;
    {
      py::gil_scoped_release release;
      const std::lock_guard<std::mutex> lock(mutex_);
      trajectory = system_->FrameTrajectory();
    }
    for (const StampedPose& p : trajectory) {
      stamps.push_back(p.timestamp);
      poses.push_back(p.world_from_camera);
    }
    return py::make_tuple(py::array_t<double>(static_cast<py::ssize_t>(stamps.size()), stamps.data()),
                          PosesArray(poses));
  }

  py::dict Statistics() const {
    SlamStatistics s;
    {
      py::gil_scoped_release release;
      const std::lock_guard<std::mutex> lock(mutex_);
      s = system_->Statistics();
    }
    py::dict d;
    d["frames"] = s.frames;
    d["tracked"] = s.tracked;
    d["keyframes"] = s.keyframes;
    d["map_points"] = s.map_points;
    d["loops"] = s.loops;
    d["relocalizations"] = s.relocalizations;
    d["resets"] = s.resets;
    return d;
  }

  void SaveMap(const std::filesystem::path& path) const {
    if (path.empty()) throw py::value_error("save_map: an empty path");
    if (std::filesystem::is_directory(path))
      throw py::value_error("save_map: " + path.string() + " is a folder; give the map file's path");
    py::gil_scoped_release release;
    const std::lock_guard<std::mutex> lock(mutex_);
    system_->SaveMap(path);
  }

 private:
  void CheckImageSize(const cv::Mat& image, const char* what) const {
    if (image.cols != camera_.width || image.rows != camera_.height) {
      throw py::value_error(std::string(what) + ": " + std::to_string(image.cols) + " x " +
                            std::to_string(image.rows) + " pixels, but the camera is " +
                            std::to_string(camera_.width) + " x " + std::to_string(camera_.height));
    }
  }

  PinholeCamera camera_;
  bool stereo_ = false;
  std::unique_ptr<SlamSystem> system_;
  // One caller at a time: Python threads may share a system, SlamSystem's calls may not overlap.
  mutable std::mutex mutex_;
  std::uint64_t next_frame_ = 0;
};

}  // namespace

void AddSystemBindings(py::module_& m) {
  py::class_<Sequence>(m, "Sequence", "An image sequence semslam reads (KITTI, synthetic city, image folder)")
      .def("__len__", &Sequence::size)
      .def("timestamp", &Sequence::Timestamp, py::arg("frame"))
      .def("image", &Sequence::Image, py::arg("frame"), py::arg("camera") = 0, "(H, W) uint8 grey image")
      .def_property_readonly("camera", &Sequence::Camera)
      .def_property_readonly("name", &Sequence::Name)
      .def("ground_truth", &Sequence::GroundTruth, "(timestamps, poses) or None");
  m.def(
      "open_sequence", [](const std::filesystem::path& path) { return Sequence(path); }, py::arg("path"),
      "Opens a KITTI odometry sequence, a KITTI raw drive, the synthetic city or an image folder.");

  py::class_<PySystem>(
      m, "System",
      "The SLAM system fed frame by frame. process() returns the frame's pose (world_from_camera, "
      "4x4, or None while not tracking) and tracking state.")
      .def(py::init<const py::dict&, const std::string&, const std::string&,
                    std::optional<std::filesystem::path>, std::optional<std::filesystem::path>,
                    const std::string&, std::optional<std::filesystem::path>>(),
           py::arg("camera"), py::arg("mode") = "mono", py::arg("pacing") = "synchronous",
           py::arg("config") = py::none(), py::arg("vocabulary") = py::none(), py::arg("segmenter") = "none",
           py::arg("labels") = py::none())
      .def("process", &PySystem::Process, py::arg("image"), py::arg("timestamp"),
           py::arg("right") = py::none(),
           "Tracks one frame; timestamp in seconds, increasing (keyframes are spaced in time)")
      .def("finish", &PySystem::Finish,
           "Lets mapping and loop closing finish and runs the final optimization")
      .def("trajectory", &PySystem::Trajectory, "(timestamps, poses) of every tracked frame")
      .def("statistics", &PySystem::Statistics)
      .def("save_map", &PySystem::SaveMap, py::arg("path"));
}

}  // namespace semslam::python
