#include "semslam/geo/gps_fusion.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "semslam/core/error.h"
#include "semslam/geometry/alignment.h"

namespace semslam {

void GpsFusionOptions::Check() const {
  sampling.Check();
  alignment.Check();
  Require(std::isfinite(translation_sigma_fraction) && translation_sigma_fraction > 0,
          "GPS fusion translation_sigma_fraction must be positive");
  Require(std::isfinite(translation_sigma_floor_m) && translation_sigma_floor_m > 0,
          "GPS fusion translation_sigma_floor_m must be positive");
  Require(std::isfinite(rotation_sigma_rad) && rotation_sigma_rad > 0,
          "GPS fusion rotation_sigma_rad must be positive");
  Require(std::isfinite(log_scale_sigma_per_sqrt_m) && log_scale_sigma_per_sqrt_m > 0,
          "GPS fusion log_scale_sigma_per_sqrt_m must be positive");
  Require(std::isfinite(prior_loss_scale) && prior_loss_scale > 0,
          "GPS fusion prior_loss_scale must be positive");
  Require(std::isfinite(line_roll_sigma_rad) && line_roll_sigma_rad > 0,
          "GPS fusion line_roll_sigma_rad must be positive");
  Require(std::isfinite(outlier_sigma) && outlier_sigma > 0, "GPS fusion outlier_sigma must be positive");
  Require(max_rounds >= 1, "GPS fusion max_rounds must be >= 1");
  Require(max_iterations >= 1, "GPS fusion max_iterations must be >= 1");
}

namespace {

struct GraphEdge {
  int a = 0, b = 0;
  Sim3d a_from_b;
  double weight = 1.0;
  bool carries_scale = true;
};

// Covisibility between keyframes of one pass: no farther apart along the keyframe chain than twice their
// distance (a revisit or a loop is much farther along the chain than apart).
std::vector<bool> WithinOnePass(const std::vector<FramePose>& keyframes,
                                const std::vector<FusionEdge>& edges) {
  std::vector<double> along(keyframes.size(), 0.0);
  for (size_t i = 1; i < keyframes.size(); ++i) {
    along[i] =
        along[i - 1] +
        (keyframes[i].world_from_camera.translation - keyframes[i - 1].world_from_camera.translation).norm();
  }
  std::vector<bool> within(edges.size(), false);
  for (size_t k = 0; k < edges.size(); ++k) {
    const FusionEdge& e = edges[k];
    if (e.kind != FusionEdgeKind::kCovisibility) continue;
    const auto a = static_cast<size_t>(e.a), b = static_cast<size_t>(e.b);
    const double chord =
        (keyframes[a].world_from_camera.translation - keyframes[b].world_from_camera.translation).norm();
    within[k] = std::abs(along[b] - along[a]) <= 2.0 * chord;
  }
  return within;
}

// A log-scale sigma that leaves an edge's scale to the rest of the graph (a factor of e at one sigma).
constexpr double kUnconstrainedLogScaleSigma = 1.0;

Sim3d Relative(const Rigid3d& world_from_a, const Rigid3d& world_from_b) {
  return Sim3d(world_from_a.Inverse() * world_from_b);
}

}  // namespace

std::optional<GpsFusionResult> FuseGps(const GpsFusionInput& input, const EnuFrame& enu_frame,
                                       const GpsFusionOptions& options) {
  options.Check();
  const std::vector<FramePose>& keyframes = input.keyframes;
  Require(!keyframes.empty(), "GPS fusion needs keyframes");
  for (size_t i = 1; i < keyframes.size(); ++i) {
    Require(keyframes[i].frame_index > keyframes[i - 1].frame_index,
            "GPS fusion: keyframes must be in strictly increasing frame order");
  }
  const int num_keyframes = static_cast<int>(keyframes.size());
  for (const FusionEdge& e : input.edges) {
    Require(e.a >= 0 && e.a < num_keyframes && e.b >= 0 && e.b < num_keyframes && e.a != e.b,
            "GPS fusion: edge between keyframes that do not exist");
    Require(std::isfinite(e.weight) && e.weight > 0, "GPS fusion: edge weight must be positive");
  }

  // 1. Samples every N frames, and the robust similarity (the paper's alignment).
  const std::vector<FramePose>& sampled_frames = input.frames.empty() ? keyframes : input.frames;
  std::vector<GpsSample> samples =
      SampleGpsPairs(Positions(sampled_frames), input.fixes, enu_frame, options.sampling);
  std::optional<GpsAlignment> prealignment;
  if (input.enu_from_map) {
    const Sim3d& given = *input.enu_from_map;
    Require(given.translation.allFinite() && given.rotation.coeffs().allFinite() &&
                std::isfinite(given.scale) && given.scale > 0,
            "GPS fusion: enu_from_map must be finite with a positive scale");
    if (static_cast<int>(samples.size()) < options.alignment.min_samples) return std::nullopt;
    prealignment = EvaluateAlignment(*input.enu_from_map, samples, options.alignment);
  } else {
    prealignment = AlignMapToGps(samples, options.alignment);
  }
  if (!prealignment) return std::nullopt;

  // 2. Nodes: keyframes, then sampled frames that are not keyframes.
  std::vector<FramePose> nodes = keyframes;
  std::map<size_t, int> node_of_frame;
  for (int i = 0; i < num_keyframes; ++i) node_of_frame[keyframes[static_cast<size_t>(i)].frame_index] = i;
  std::map<size_t, const FramePose*> frame_by_index;
  for (const FramePose& f : sampled_frames) frame_by_index[f.frame_index] = &f;
  std::vector<int> sample_node(samples.size());
  std::vector<GraphEdge> edges;
  const auto keyframe_at_or_before = [&](size_t frame) -> int {
    const auto it = std::upper_bound(keyframes.begin(), keyframes.end(), frame,
                                     [](size_t f, const FramePose& k) { return f < k.frame_index; });
    return static_cast<int>(it - keyframes.begin()) - 1;  // -1: none
  };
  for (size_t s = 0; s < samples.size(); ++s) {
    const size_t frame = samples[s].frame_index;
    const auto existing = node_of_frame.find(frame);
    if (existing != node_of_frame.end()) {
      sample_node[s] = existing->second;
      continue;
    }
    const FramePose& pose = *frame_by_index.at(frame);
    const int node = static_cast<int>(nodes.size());
    nodes.push_back(pose);
    node_of_frame[frame] = node;
    sample_node[s] = node;
    const int before = keyframe_at_or_before(frame);
    const int after = before + 1;
    if (before >= 0) {
      edges.push_back(
          {before, node,
           Relative(keyframes[static_cast<size_t>(before)].world_from_camera, pose.world_from_camera), 1.0});
    }
    if (after < num_keyframes) {
      edges.push_back(
          {node, after,
           Relative(pose.world_from_camera, keyframes[static_cast<size_t>(after)].world_from_camera), 1.0});
    }
  }

  // 3. Edges between keyframes: the caller's, and the chain where the caller gave none.
  std::set<std::pair<int, int>> given;
  const std::vector<bool> within_one_pass = WithinOnePass(keyframes, input.edges);
  for (size_t k = 0; k < input.edges.size(); ++k) {
    const FusionEdge& e = input.edges[k];
    const bool carries_scale = options.one_pass_covisibility_carries_scale || !within_one_pass[k];
    edges.push_back({e.a, e.b, e.a_from_b, e.weight, carries_scale});
    given.insert({std::min(e.a, e.b), std::max(e.a, e.b)});
  }
  if (options.add_chain_edges) {
    for (int i = 1; i < num_keyframes; ++i) {
      if (given.count({i - 1, i}) > 0) continue;
      edges.push_back({i - 1, i,
                       Relative(keyframes[static_cast<size_t>(i - 1)].world_from_camera,
                                keyframes[static_cast<size_t>(i)].world_from_camera),
                       1.0});
    }
  }

  // 4. Solve with every fix, the Cauchy scale graduated down to prior_loss_scale; then drop the fixes far
  // from the fused trajectory and solve again until the set settles.
  const Sim3d& enu_from_map = prealignment->enu_from_map;
  const double units_per_metre = 1.0 / enu_from_map.scale;
  const bool fix_scale = !options.alignment.estimate_scale;
  std::vector<bool> active(samples.size(), true);
  GpsFusionResult result{
      Georeference(enu_frame, enu_from_map), *prealignment, samples, {}, {}, 0, 0.0, {}, 0, {}};
  std::vector<Sim3d> fused(nodes.size());
  for (size_t i = 0; i < nodes.size(); ++i) fused[i] = enu_from_map * Sim3d(nodes[i].world_from_camera);
  const bool along_line = prealignment->roll_from_camera_down;
  std::vector<Eigen::Vector3d> down_targets;
  if (along_line) {
    for (const Sim3d& f : fused) down_targets.push_back(f.rotation * Eigen::Vector3d::UnitY());
  }
  const auto antenna_residuals = [&] {
    std::vector<double> residuals(samples.size());
    for (size_t s = 0; s < samples.size(); ++s) {
      const Sim3d& node = fused[static_cast<size_t>(sample_node[s])];
      residuals[s] = (node.translation + node.rotation * options.antenna_in_camera_m - samples[s].enu).norm();
    }
    return residuals;
  };
  // The first scale: the 90th percentile of the samples' distances from the similarity, in sigmas.
  std::vector<double> spread;
  {
    const std::vector<double> initial = antenna_residuals();
    for (size_t s = 0; s < samples.size(); ++s) spread.push_back(initial[s] / samples[s].sigma_m);
    std::sort(spread.begin(), spread.end());
  }
  double loss_scale = std::max(options.prior_loss_scale, spread[spread.size() * 9 / 10]);
  const auto solve = [&] {
    PoseGraph graph;
    for (const Sim3d& n : fused) graph.AddNode(n, false);
    for (const GraphEdge& e : edges) {
      const double length = e.a_from_b.translation.norm();
      const double sigma_t = std::max(options.translation_sigma_fraction * length,
                                      options.translation_sigma_floor_m * units_per_metre);
      const double sigma_s =
          e.carries_scale
              ? options.log_scale_sigma_per_sqrt_m *
                    std::sqrt(std::max(length / units_per_metre, options.translation_sigma_floor_m))
              : kUnconstrainedLogScaleSigma;
      graph.AddRelativeEdge(
          e.a, e.b, e.a_from_b,
          e.weight * PoseGraph::EdgeInformation(sigma_t, options.rotation_sigma_rad, sigma_s));
    }
    for (size_t i = 0; i < down_targets.size(); ++i) {
      graph.AddDirectionPrior(static_cast<int>(i), Eigen::Vector3d::UnitY(), down_targets[i],
                              options.line_roll_sigma_rad);
    }
    for (size_t s = 0; s < samples.size(); ++s) {
      if (active[s]) {
        graph.AddPositionPrior(sample_node[s], samples[s].enu, samples[s].sigma_m, true,
                               options.antenna_in_camera_m);
      }
    }
    PoseGraphOptions graph_options;
    graph_options.fix_scale = fix_scale;
    graph_options.max_iterations = options.max_iterations;
    graph_options.prior_loss = RobustLoss::kCauchy;
    graph_options.prior_loss_scale = loss_scale;
    result.summary = graph.Optimize(graph_options);
    ++result.rounds;
    for (size_t i = 0; i < nodes.size(); ++i) fused[i] = graph.world_from_node(static_cast<int>(i));
  };
  while (loss_scale > options.prior_loss_scale) {
    solve();
    loss_scale = std::max(options.prior_loss_scale, 0.5 * loss_scale);
  }
  for (int round = 0; round < options.max_rounds; ++round) {
    solve();
    result.residuals_m = antenna_residuals();
    std::vector<bool> next(samples.size());
    for (size_t s = 0; s < samples.size(); ++s)
      next[s] = result.residuals_m[s] <= options.outlier_sigma * samples[s].sigma_m;
    // Done when the kept fixes settle, at the last round, or when too few would be left.
    if (next == active || round + 1 == options.max_rounds ||
        std::count(next.begin(), next.end(), true) < options.alignment.min_samples) {
      break;
    }
    active = std::move(next);
  }
  result.inliers = active;
  double sum = 0.0;
  for (size_t s = 0; s < samples.size(); ++s) {
    if (!active[s]) continue;
    ++result.num_inliers;
    sum += result.residuals_m[s] * result.residuals_m[s];
  }
  if (result.num_inliers > 0) result.inlier_rmse_m = std::sqrt(sum / result.num_inliers);

  // 5. Outputs: fused keyframe poses, per-node corrections and the global fit.
  result.keyframe_enu_from_camera.assign(fused.begin(), fused.begin() + num_keyframes);
  std::vector<LocalCorrections::Keyframe> corrections;
  Points3d map_positions, enu_positions;
  for (size_t i = 0; i < nodes.size(); ++i) {
    const Sim3d correction = fused[i] * Sim3d(nodes[i].world_from_camera).Inverse();
    corrections.push_back({nodes[i].frame_index, nodes[i].world_from_camera.translation, correction});
    map_positions.push_back(nodes[i].world_from_camera.translation);
    enu_positions.push_back(fused[i].translation);
  }
  std::optional<Sim3d> global;
  if (along_line) {
    Eigen::Vector3d map_down = Eigen::Vector3d::Zero();
    for (const FramePose& n : nodes) map_down += n.world_from_camera.rotation * Eigen::Vector3d::UnitY();
    global = AlignAlongLine(map_positions, enu_positions, map_down, !fix_scale);
  } else if (fix_scale) {
    if (const auto rigid = AlignRigid3(map_positions, enu_positions)) global = Sim3d(*rigid);
  } else {
    global = AlignSim3(map_positions, enu_positions);
  }
  result.georeference = Georeference(enu_frame, global.value_or(enu_from_map),
                                     std::make_shared<const LocalCorrections>(std::move(corrections)));
  return result;
}

}  // namespace semslam
