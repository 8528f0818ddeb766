#pragma once
// The Python module `semslam` (pybind11): what each part registers, and NumPy conversions they share.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <vector>

#include "semslam/geometry/camera.h"
#include "semslam/geometry/rigid3.h"
#include "semslam/geometry/trajectory.h"

namespace semslam::python {

namespace py = pybind11;

// K x 4 x 4 float64 array of poses (world_from_camera as homogeneous matrices).
py::array_t<double> PosesArray(const std::vector<Rigid3d>& poses);
// One 4 x 4 matrix.
py::array_t<double> PoseArray(const Rigid3d& pose);
// {"width", "height", "fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"}.
py::dict CameraDict(const PinholeCamera& camera);
// A trajectory from (timestamps (N), poses (N x 4 x 4)) arrays; throws ValueError on bad shapes.
Trajectory TrajectoryFromArrays(const py::array_t<double>& timestamps, const py::array_t<double>& poses);

void AddMapBindings(py::module_& m);
void AddSystemBindings(py::module_& m);

}  // namespace semslam::python
