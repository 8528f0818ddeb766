// The compiled part of the Python package `semslam` (the extension semslam._semslam, which
// python/semslam/__init__.py re-exports): maps, trajectories, evaluation and a SLAM system fed from Python.

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cmath>
#include <optional>
#include <string>

#include "bindings.h"
#include "semslam/core/error.h"
#include "semslam/eval/trajectory_metrics.h"
#include "semslam/io/trajectory_io.h"
#include "semslam_build_info.h"

namespace semslam::python {

py::dict CameraDict(const PinholeCamera& c) {
  py::dict d;
  d["width"] = c.width;
  d["height"] = c.height;
  d["fx"] = c.fx;
  d["fy"] = c.fy;
  d["cx"] = c.cx;
  d["cy"] = c.cy;
  d["k1"] = c.distortion.k1;
  d["k2"] = c.distortion.k2;
  d["p1"] = c.distortion.p1;
  d["p2"] = c.distortion.p2;
  d["k3"] = c.distortion.k3;
  return d;
}

py::array_t<double> PoseArray(const Rigid3d& pose) {
  py::array_t<double> out({4, 4});
  auto m = out.mutable_unchecked<2>();
  const Eigen::Matrix4d matrix = pose.ToMatrix4();
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) m(r, c) = matrix(r, c);
  }
  return out;
}

py::array_t<double> PosesArray(const std::vector<Rigid3d>& poses) {
  py::array_t<double> out({static_cast<py::ssize_t>(poses.size()), py::ssize_t{4}, py::ssize_t{4}});
  auto m = out.mutable_unchecked<3>();
  for (size_t k = 0; k < poses.size(); ++k) {
    const Eigen::Matrix4d matrix = poses[k].ToMatrix4();
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) m(static_cast<py::ssize_t>(k), r, c) = matrix(r, c);
    }
  }
  return out;
}

Trajectory TrajectoryFromArrays(const py::array_t<double>& timestamps, const py::array_t<double>& poses) {
  if (timestamps.ndim() != 1) throw py::value_error("timestamps must be a 1-D array");
  if (poses.ndim() != 3 || poses.shape(1) != 4 || poses.shape(2) != 4 ||
      poses.shape(0) != timestamps.shape(0)) {
    throw py::value_error("poses must be an N x 4 x 4 array, one per timestamp");
  }
  const auto t = timestamps.unchecked<1>();
  const auto p = poses.unchecked<3>();
  Trajectory trajectory;
  for (py::ssize_t i = 0; i < timestamps.shape(0); ++i) {
    const std::string which = "poses[" + std::to_string(i) + "]";
    if (!std::isfinite(t(i))) throw py::value_error("timestamps[" + std::to_string(i) + "] is not finite");
    Eigen::Matrix4d m;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) m(r, c) = p(i, r, c);
    }
    if (!m.allFinite()) throw py::value_error(which + " holds a value that is not finite");
    if (!m.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1), 1e-9))
      throw py::value_error(which + ": the bottom row of a rigid transform is 0 0 0 1");
    // A rotation within what trajectory files are allowed; the pose is re-orthonormalized.
    const Eigen::Matrix3d rotation = m.topLeftCorner<3, 3>();
    if (!IsRotation(rotation)) {
      throw py::value_error(which + ": its upper-left 3 x 3 is not a rotation (largest |R^T R - I| entry " +
                            std::to_string(OrthonormalityDeviation(rotation)) + ")");
    }
    trajectory.push_back({t(i), Rigid3d::FromMatrix(Eigen::Matrix3x4d(m.topRows<3>()))});
  }
  return trajectory;
}

namespace {

py::tuple TrajectoryTuple(const Trajectory& trajectory) {
  py::array_t<double> stamps(static_cast<py::ssize_t>(trajectory.size()));
  std::vector<Rigid3d> poses;
  auto s = stamps.mutable_unchecked<1>();
  for (size_t i = 0; i < trajectory.size(); ++i) {
    s(static_cast<py::ssize_t>(i)) = trajectory[i].timestamp;
    poses.push_back(trajectory[i].world_from_camera);
  }
  return py::make_tuple(stamps, PosesArray(poses));
}

py::object OrNone(const std::optional<double>& v) { return v ? py::object(py::float_(*v)) : py::none(); }

py::dict EvaluationDict(const TrajectoryEvaluation& e) {
  py::dict d;
  d["alignment"] = std::string(AlignmentName(e.alignment));
  d["estimate_poses"] = e.estimate_poses;
  d["truth_poses"] = e.truth_poses;
  d["matched"] = e.matched;
  d["path_length_m"] = e.path_length_m;
  d["ate_rmse"] = e.ate.rmse;
  d["ate_mean"] = e.ate.mean;
  d["ate_median"] = e.ate.median;
  d["ate_std"] = e.ate.std;
  d["ate_max"] = e.ate.max;
  d["scale"] = e.ate.scale;
  d["alignment_fallback"] = e.ate.alignment_fallback;
  d["rpe_trans_rmse_m"] = e.rpe ? py::object(py::float_(e.rpe->trans_rmse_m)) : py::none();
  d["rpe_rot_rmse_deg"] = e.rpe ? py::object(py::float_(e.rpe->rot_rmse_deg)) : py::none();
  d["kitti_trans_pct"] = OrNone(e.kitti.trans_pct);
  d["kitti_rot_deg_per_100m"] = OrNone(e.kitti.rot_deg_per_100m);
  return d;
}

bool IsPath(const py::handle& object) {
  return py::isinstance<py::str>(object) || py::hasattr(object, "__fspath__");
}

Trajectory TrajectoryOf(const py::object& object, const char* what) {
  if (IsPath(object)) return ReadTrajectory(py::cast<std::filesystem::path>(object));
  if (py::isinstance<py::tuple>(object) && py::len(object) == 2) {
    const py::tuple pair = object;
    return TrajectoryFromArrays(pair[0].cast<py::array_t<double>>(), pair[1].cast<py::array_t<double>>());
  }
  throw py::type_error(std::string(what) + ": a file path or a (timestamps, poses) tuple");
}

}  // namespace

}  // namespace semslam::python

PYBIND11_MODULE(_semslam, m) {
  using namespace semslam;
  using namespace semslam::python;
  m.doc() = "semslam: visual semantic SLAM with landmarks (maps, trajectories, evaluation, a SLAM system)";
  m.attr("__version__") = std::string(build_info::kVersion);
  m.attr("commit") = std::string(build_info::kCommit);

  // Input errors become ValueError (with file, line and field), bad arguments ValueError too.
  py::register_exception<InputError>(m, "InputError", PyExc_ValueError);
  py::register_exception<InvalidArgument>(m, "InvalidArgument", PyExc_ValueError);

  m.def(
      "read_trajectory",
      [](const std::filesystem::path& path, std::optional<std::filesystem::path> times) {
        return TrajectoryTuple(ReadTrajectory(path, times));
      },
      py::arg("path"), py::arg("times") = py::none(),
      "Reads a TUM or KITTI trajectory file: (timestamps (N,), poses (N, 4, 4) world_from_camera). KITTI "
      "files take their stamps from `times` (a times.txt) or their line index.");

  m.def(
      "evaluate",
      [](const py::object& estimate, const py::object& truth, const std::string& align,
         std::optional<std::filesystem::path> times, double max_dt,
         std::optional<std::pair<size_t, size_t>> frames) {
        EvalOptions options;
        options.alignment = ParseAlignment(align);
        options.max_dt = max_dt;
        if (IsPath(estimate) && IsPath(truth)) {
          FrameRange range;
          if (frames) range = FrameRange{frames->first, frames->second};
          return EvaluationDict(EvaluateTrajectoryFiles(py::cast<std::filesystem::path>(estimate),
                                                        py::cast<std::filesystem::path>(truth), times,
                                                        options, range));
        }
        // A file's frame range and KITTI times have no meaning for arrays that carry their stamps.
        if (frames || times)
          throw py::value_error(
              "frames and times apply to trajectory files, not to (timestamps, poses) arrays");
        return EvaluationDict(
            EvaluateTrajectory(TrajectoryOf(estimate, "estimate"), TrajectoryOf(truth, "truth"), options));
      },
      py::arg("estimate"), py::arg("truth"), py::arg("align") = "sim3", py::arg("times") = py::none(),
      py::arg("max_dt") = 0.02, py::arg("frames") = py::none(),
      "ATE, RPE and KITTI errors of `estimate` against `truth` (each a file path or a (timestamps, poses) "
      "tuple), as `semslam eval` prints them. align: 'sim3' (monocular), 'se3' (stereo) or 'none'.");

  AddMapBindings(m);
  AddSystemBindings(m);
}
