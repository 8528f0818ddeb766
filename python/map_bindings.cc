// semslam.load_map: a map.semslam as NumPy arrays.

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <string>

#include "bindings.h"
#include "semslam/core/error.h"
#include "semslam/map/map.h"
#include "semslam/map/map_file.h"
#include "semslam/semantics/class_table.h"
#include "semslam/semantics/semantic_outputs.h"

namespace semslam::python {

namespace {

struct LoadedMap {
  py::array_t<double> points;              // N x 3, map frame
  py::array_t<std::int32_t> labels;        // N, Cityscapes trainId, -1 unlabeled
  py::array_t<float> confidence;           // N, posterior of the label
  py::array_t<std::int32_t> observations;  // N, segmentations fused
  py::array_t<double> keyframe_poses;      // K x 4 x 4 world_from_camera
  py::array_t<std::int64_t> keyframe_ids, keyframe_frames;
  py::array_t<double> keyframe_timestamps;
  py::list landmarks;       // dicts from the "geo" section
  py::object topology;      // {"nodes": [...], "edges": [...], ...} from the "topology" section, or None
  py::object georeference;  // {"origin", "enu_from_map", ...} of the landmarks' map, or None
  py::dict georeferences;   // map id -> georeference, for every map of the atlas in the world
  py::dict cameras;         // map id -> {"nominal": {...}, "camera": {...}, "refined": bool}
  py::list class_names;     // by trainId
  std::map<std::string, std::string> sections;  // every extra section, as text
};

py::object ParseJson(const std::string& text) { return py::module_::import("json").attr("loads")(text); }

// The "geo" section: landmarks and the georeference of each map in the world.
void ReadGeoSection(const py::dict& geo, LoadedMap& out) {
  if (geo.contains("landmarks")) out.landmarks = geo["landmarks"];
  if (geo.contains("georeference")) out.georeference = geo["georeference"];  // version 1: one map
  if (geo.contains("maps")) {
    for (const py::handle entry : geo["maps"].cast<py::list>()) {
      const py::dict e = entry.cast<py::dict>();
      out.georeferences[e["map"]] = e["georeference"];
    }
    if (geo.contains("landmarks_map") && out.georeferences.contains(geo["landmarks_map"]))
      out.georeference = out.georeferences[geo["landmarks_map"]];
  }
}

LoadedMap LoadMap(const std::filesystem::path& path) {
  if (path.empty()) throw py::value_error("load_map: an empty path");
  Map map;
  const MapFileContents contents = ReadMapFile(path, map);
  LoadedMap out;
  std::vector<SemanticPoint> points;
  for (const MapPoint* p : map.MapPoints()) {
    if (!p->is_bad()) points.push_back(ToSemanticPoint(p->position(), p->labels()));
  }
  const auto n = static_cast<py::ssize_t>(points.size());
  out.points = py::array_t<double>({n, py::ssize_t{3}});
  out.labels = py::array_t<std::int32_t>(n);
  out.confidence = py::array_t<float>(n);
  out.observations = py::array_t<std::int32_t>(n);
  auto xyz = out.points.mutable_unchecked<2>();
  auto labels = out.labels.mutable_unchecked<1>();
  auto confidence = out.confidence.mutable_unchecked<1>();
  auto observations = out.observations.mutable_unchecked<1>();
  for (py::ssize_t i = 0; i < n; ++i) {
    const SemanticPoint& p = points[static_cast<size_t>(i)];
    for (int a = 0; a < 3; ++a) xyz(i, a) = p.position[a];
    labels(i) = IsValidTrainId(p.label) ? p.label : -1;
    confidence(i) = p.confidence;
    observations(i) = p.observations;
  }
  std::vector<Rigid3d> poses;
  std::vector<std::int64_t> ids, frames;
  std::vector<double> stamps;
  for (const KeyFrame* kf : map.KeyFrames()) {
    if (kf->is_bad()) continue;
    poses.push_back(kf->world_from_camera());
    ids.push_back(static_cast<std::int64_t>(kf->id()));
    frames.push_back(static_cast<std::int64_t>(kf->frame_id()));
    stamps.push_back(kf->timestamp());
  }
  out.keyframe_poses = PosesArray(poses);
  out.keyframe_ids = py::array_t<std::int64_t>(static_cast<py::ssize_t>(ids.size()), ids.data());
  out.keyframe_frames = py::array_t<std::int64_t>(static_cast<py::ssize_t>(frames.size()), frames.data());
  out.keyframe_timestamps = py::array_t<double>(static_cast<py::ssize_t>(stamps.size()), stamps.data());
  out.topology = py::none();
  out.georeference = py::none();
  if (const auto it = contents.extra_sections.find("topology"); it != contents.extra_sections.end()) {
    out.topology = ParseJson(it->second);
  }
  if (const auto it = contents.extra_sections.find("geo"); it != contents.extra_sections.end()) {
    try {
      ReadGeoSection(ParseJson(it->second), out);
    } catch (const std::exception& e) {
      // Not JSON or a key missing (error_already_set), a value's type (cast_error).
      throw InputError(path, "section 'geo': " + std::string(e.what()));
    }
  }
  for (const auto& [map_id, camera] : contents.cameras) {
    py::dict entry;
    entry["nominal"] = CameraDict(camera.nominal);
    entry["camera"] = CameraDict(camera.camera);
    entry["refined"] = camera.refined();
    out.cameras[py::int_(map_id)] = entry;
  }
  for (int c = 0; c < kNumClasses; ++c) out.class_names.append(std::string(ClassName(c)));
  out.sections = contents.extra_sections;
  return out;
}

}  // namespace

void AddMapBindings(py::module_& m) {
  py::class_<LoadedMap>(
      m, "SemanticMap",
      "A map read from map.semslam. Positions are in the map frame (the first camera's: x right, "
      "y down, z forward), in map units for a monocular run (see georeference for metres).")
      .def_readonly("points", &LoadedMap::points, "(N, 3) float64 map points")
      .def_readonly("labels", &LoadedMap::labels, "(N,) int32 Cityscapes trainIds, -1 for unlabeled")
      .def_readonly("confidence", &LoadedMap::confidence, "(N,) float32 posterior of each label")
      .def_readonly("observations", &LoadedMap::observations,
                    "(N,) int32 segmentations fused into each point")
      .def_readonly("keyframe_poses", &LoadedMap::keyframe_poses, "(K, 4, 4) float64 world_from_camera")
      .def_readonly("keyframe_ids", &LoadedMap::keyframe_ids)
      .def_readonly("keyframe_frames", &LoadedMap::keyframe_frames, "(K,) frame index of each keyframe")
      .def_readonly("keyframe_timestamps", &LoadedMap::keyframe_timestamps)
      .def_readonly("landmarks", &LoadedMap::landmarks, "placed landmarks (dicts), empty without GPS")
      .def_readonly("topology", &LoadedMap::topology, "the topological map as topology.json has it, or None")
      .def_readonly("georeference", &LoadedMap::georeference,
                    "map -> ENU -> WGS84 of the map the landmarks were placed in, or None without GPS")
      .def_readonly("georeferences", &LoadedMap::georeferences,
                    "map id -> georeference of every map in the world (a map not named has none)")
      .def_readonly(
          "cameras", &LoadedMap::cameras,
          "per map id: the sensor's nominal camera, the camera the map was fitted to (the final BA's "
          "refinement, with k1, k2, when `refined`), as dicts of width, height, fx, fy, cx, cy, k1, k2, "
          "p1, p2, k3")
      .def_readonly("class_names", &LoadedMap::class_names, "class names by trainId")
      .def_readonly("sections", &LoadedMap::sections, "every extra section of the file, as text")
      .def("__repr__", [](const LoadedMap& map) {
        return "<semslam.SemanticMap: " + std::to_string(map.points.shape(0)) + " points, " +
               std::to_string(map.keyframe_poses.shape(0)) + " keyframes>";
      });
  m.def("load_map", &LoadMap, py::arg("path"), "Reads a map.semslam written by `semslam run`.");
}

}  // namespace semslam::python
