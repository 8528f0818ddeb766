#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <bit>
#include <numeric>
#include <random>

#include "semslam/geo/georeference.h"
#include "semslam/report/class_colors.h"
#include "semslam/report/html_encoding.h"
#include "semslam/report/html_report_internal.h"
#include "semslam/semantics/class_table.h"

namespace semslam::html_report {

namespace {

// ---------------------------------------------------------------------------------------------------------
// The 3D view's data.

void AppendFloat32(std::string& bytes, double value) {
  const auto bits = std::bit_cast<std::uint32_t>(static_cast<float>(value));
  for (int k = 0; k < 4; ++k) bytes.push_back(static_cast<char>((bits >> (8 * k)) & 0xffu));  // little-endian
}

// Indices of a seeded random subset of `count` of `total` items, in increasing order.
std::vector<std::size_t> SampleIndices(std::size_t total, std::size_t count, std::uint64_t seed) {
  std::vector<std::size_t> indices(total);
  std::iota(indices.begin(), indices.end(), std::size_t{0});
  if (count >= total) return indices;
  std::mt19937_64 rng(seed);
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t j = i + static_cast<std::size_t>(rng() % (total - i));
    std::swap(indices[i], indices[j]);
  }
  indices.resize(count);
  std::sort(indices.begin(), indices.end());
  return indices;
}

// Evenly spaced indices (first and last included).
std::vector<std::size_t> EvenIndices(std::size_t total, std::size_t count) {
  std::vector<std::size_t> indices;
  if (total <= count) {
    indices.resize(total);
    std::iota(indices.begin(), indices.end(), std::size_t{0});
    return indices;
  }
  for (std::size_t i = 0; i < count; ++i) {
    indices.push_back(static_cast<std::size_t>(std::llround(
        static_cast<double>(i) * static_cast<double>(total - 1) / static_cast<double>(count - 1))));
  }
  return indices;
}


double Percentile(std::vector<double> values, double q) {
  const auto k = static_cast<std::size_t>(q * static_cast<double>(values.size() - 1));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

}  // namespace

ViewData BuildViewData(const ReportInputs& in, const HtmlReportOptions& options) {
  ViewData view;
  json& data = view.data;
  // The display frame: x east, y north, z up (ENU, metres) with a georeference; else the level map frame (x
  // right and y forward of the first camera, z up), in map units for a monocular run.
  const Sim3d display_from_map = in.enu_from_map ? *in.enu_from_map : LevelFromCameraWorld();
  const auto display = [&](const Eigen::Vector3d& p) -> Eigen::Vector3d { return display_from_map * p; };
  const JsonFields f(in.run_dir / "run.json");
  const bool stereo = f.String(in.run, "mode", "mode").value_or("mono") == "stereo";
  data["frame"] = in.enu_from_map ? "enu" : "level";
  data["units"] = in.enu_from_map || stereo ? "m" : "map units";

  // Classes as the plots show them: listed ones in distinct colours, the rest (and unlabeled points) as "other".
  std::array<long long, kNumClasses> counts{};
  long long other_count = 0;
  if (in.points) {
    for (const SemanticPoint& p : *in.points) {
      if (IsValidTrainId(p.label)) ++counts[static_cast<std::size_t>(p.label)];
    }
  }
  const ClassDisplay classes_shown = MakeClassDisplay(counts);
  const auto key_of = [&](int label) {
    return IsValidTrainId(label) && classes_shown.listed[static_cast<std::size_t>(label)] ? label : kNoLabel;
  };
  auto slot = [](int key) { return key == kNoLabel ? kNumClasses : key; };
  std::array<long long, kNumClasses + 1> map_counts{};
  std::array<long long, kNumClasses + 1> shown_counts{};
  std::vector<std::size_t> chosen;
  if (in.points) {
    for (const SemanticPoint& p : *in.points) ++map_counts[static_cast<std::size_t>(slot(key_of(p.label)))];
    other_count = map_counts[kNumClasses];
    // Points: a seeded random subset, sorted by class so that a class is one contiguous range.
    chosen = SampleIndices(in.points->size(), options.max_points, options.seed);
    std::stable_sort(chosen.begin(), chosen.end(), [&](std::size_t a, std::size_t b) {
      return slot(key_of((*in.points)[a].label)) < slot(key_of((*in.points)[b].label));
    });
    std::string positions, labels;
    positions.reserve(chosen.size() * 12);
    labels.reserve(chosen.size());
    json ranges = json::array();
    for (std::size_t i = 0; i < chosen.size(); ++i) {
      const SemanticPoint& p = (*in.points)[chosen[i]];
      const int key = key_of(p.label);
      const Eigen::Vector3d q = display(p.position);
      for (int axis = 0; axis < 3; ++axis) AppendFloat32(positions, q[axis]);
      labels.push_back(static_cast<char>(key));
      ++shown_counts[static_cast<std::size_t>(slot(key))];
      if (ranges.empty() || ranges.back()[0].get<int>() != key) ranges.push_back({key, i, 0});
      ranges.back()[2] = ranges.back()[2].get<std::size_t>() + 1;
    }
    view.points_shown = chosen.size();
    data["points"] = {{"total", in.points->size()},
                      {"count", chosen.size()},
                      {"positions_b64", Base64Encode(positions)},
                      {"labels_b64", Base64Encode(labels)},
                      {"class_ranges", ranges}};
  }
  json classes = json::array();
  for (int c = 0; c < kNumClasses; ++c) {
    if (!classes_shown.listed[static_cast<std::size_t>(c)]) continue;
    const Rgb color = classes_shown.color[static_cast<std::size_t>(c)];
    classes.push_back({{"id", c},
                       {"name", std::string(ClassName(c))},
                       {"color", {color.r, color.g, color.b}},
                       {"map_count", map_counts[static_cast<std::size_t>(c)]},
                       {"shown", shown_counts[static_cast<std::size_t>(c)]}});
  }
  std::stable_sort(classes.begin(), classes.end(), [](const json& a, const json& b) {
    return a["map_count"].get<long long>() > b["map_count"].get<long long>();
  });
  if (other_count > 0) {
    const Rgb color = classes_shown.other;
    classes.push_back({{"id", kNoLabel},
                       {"name", "other classes, unlabeled"},
                       {"color", {color.r, color.g, color.b}},
                       {"map_count", other_count},
                       {"shown", shown_counts[kNumClasses]}});
  }
  data["classes"] = classes;

  Eigen::AlignedBox3d box;
  std::vector<double> heights;
  auto positions_b64 = [&](const Trajectory& trajectory, const std::vector<std::size_t>& indices, bool frame) {
    std::string bytes;
    bytes.reserve(indices.size() * 12);
    for (const std::size_t i : indices) {
      const Eigen::Vector3d t = display(trajectory[i].world_from_camera.translation);
      box.extend(t);
      if (frame) heights.push_back(t.z());
      for (int axis = 0; axis < 3; ++axis) AppendFloat32(bytes, t[axis]);
    }
    return Base64Encode(bytes);
  };
  if (in.trajectory) {
    const std::vector<std::size_t> indices = EvenIndices(in.trajectory->size(), options.max_trajectory_poses);
    view.trajectory_poses = indices.size();
    data["trajectory"] = {{"total", in.trajectory->size()},
                          {"count", indices.size()},
                          {"positions_b64", positions_b64(*in.trajectory, indices, true)}};
  }
  if (in.keyframes) {
    // Thinned on long runs: a thousand dots hide the trajectory they sit on.
    const std::vector<std::size_t> indices = EvenIndices(in.keyframes->size(), options.max_keyframes);
    view.keyframes_shown = indices.size();
    data["keyframes"] = {{"total", in.keyframes->size()},
                         {"count", indices.size()},
                         {"positions_b64", positions_b64(*in.keyframes, indices, heights.empty())}};
  }
  json landmarks = json::array();
  if (in.landmarks) {
    for (const LandmarkRow& row : *in.landmarks) {
      if (!row.map_xyz) continue;
      const Eigen::Vector3d q = display(*row.map_xyz);
      box.extend(q);
      landmarks.push_back({{"name", row.name}, {"position", {q[0], q[1], q[2]}}});
    }
  }
  data["landmarks"] = landmarks;

  // The initial view: the trajectory, the landmarks and the bulk of the points (2nd to 98th percentile per
  // axis, so that a few far points do not shrink everything else to a dot).
  if (!chosen.empty()) {
    Eigen::Vector3d low, high;
    for (int axis = 0; axis < 3; ++axis) {
      std::vector<double> values;
      values.reserve(chosen.size());
      for (const std::size_t i : chosen) values.push_back(display((*in.points)[i].position)[axis]);
      low[axis] = Percentile(values, 0.02);
      high[axis] = Percentile(values, 0.98);
    }
    box.extend(low);
    box.extend(high);
  }
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 1.0;
  if (!box.isEmpty()) {
    center = box.center();
    radius = std::max(0.5 * box.diagonal().norm(), 1e-3);
  }
  // The grid lies at the cameras' median height (the road is a camera height below, but cameras are what is known).
  const double grid_z = heights.empty() ? center.z() : Percentile(heights, 0.5);
  data["view"] = {{"center", {center[0], center[1], center[2]}}, {"radius", radius}, {"grid_z", grid_z}};
  return view;
}

void AppendMapView(Page& page, const ReportInputs& in, const ViewData& view) {
  page.Open("map3d", "Semantic map in 3D");
  page.body += fmt::format(
      "<p>{} {} of {} map points shown{}. Drag to rotate, wheel to zoom, shift-drag or right-drag to pan; "
      "click a class to hide or show it.</p>\n",
      view.data.value("frame", "") == "enu"
          ? "Seen from above, north up (east, north, up; metres), with a grid."
          : std::string("Seen from above in the map frame (the first camera looking up the page), with a grid in ") +
                view.data.value("units", "map units") + ": no georeference, so no north.",
      GroupThousands(static_cast<long long>(view.points_shown)),
      GroupThousands(static_cast<long long>(in.points ? in.points->size() : 0)),
      in.points && view.points_shown < in.points->size() ? " (a random subset)" : "");
  page.body += R"HTML(<div class="viewer">
<div class="canvas-wrap" id="view-wrap"><canvas id="view-canvas"></canvas><canvas id="view-overlay"></canvas>
<div class="view-status" id="view-status">loading&hellip;</div></div>
<div class="view-side">
<div class="buttons">
<button type="button" id="view-reset">Reset view</button>
<button type="button" id="view-top">Top view</button>
<button type="button" id="view-oblique">3D view</button>
<button type="button" id="view-background">Background</button>
</div>
<label class="slider">point size <input type="range" id="view-point-size" min="1" max="8" step="0.5" value="2"></label>
<div class="toggles">
<label><input type="checkbox" id="show-trajectory" checked> <span class="swatch" style="background:#0a58ca"></span>trajectory</label>
<label><input type="checkbox" id="show-keyframes" checked> <span class="swatch" style="background:#ff8c00"></span>keyframes</label>
<label><input type="checkbox" id="show-landmarks" checked> <span class="swatch" style="background:#d6008f"></span>landmarks</label>
<label><input type="checkbox" id="show-grid" checked> <span class="swatch" style="background:#b8c0c8"></span>grid</label>
</div>
<div class="buttons"><button type="button" id="classes-all">All classes</button>
<button type="button" id="classes-none">No class</button></div>
<table class="legend" id="legend"><thead><tr><th>class</th><th class="num">map</th><th class="num">shown</th></tr></thead>
<tbody></tbody></table>
</div>
</div>
)HTML";
  page.Close();
}

}  // namespace semslam::html_report
