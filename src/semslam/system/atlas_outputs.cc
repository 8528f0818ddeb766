#include "semslam/system/atlas_outputs.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>

#include "semslam/core/atomic_file.h"
#include "semslam/core/text_reader.h"
#include "semslam/semantics/class_table.h"

namespace semslam {

nlohmann::json LoopEventJson(const LoopEvent& e) {
  return {{"query_keyframe", e.query_keyframe},
          {"matched_keyframe", e.matched_keyframe},
          {"timestamp", e.query_timestamp},
          {"matched_timestamp", e.matched_timestamp},
          {"matches", e.matches},
          {"scale", e.scale}};
}

nlohmann::json AtlasJson(const SlamSystem& slam) {
  const SlamStatistics stats = slam.Statistics();
  const std::map<std::uint32_t, size_t> frames_per_map = slam.TrackedFramesPerMap();
  const std::uint32_t main = slam.MainMapId();
  size_t unmerged = 0;
  nlohmann::json per_map = nlohmann::json::object();
  for (const auto& [map_id, frames] : frames_per_map) {
    per_map[std::to_string(map_id)] = frames;
    if (map_id != main) unmerged += frames;
  }
  nlohmann::json merges = nlohmann::json::array();
  for (const LoopEvent& e : slam.Merges()) {
    nlohmann::json merge = LoopEventJson(e);
    merge["merged_map"] = e.map_id;
    merge["into_map"] = e.matched_map_id;
    merge["verified_neighbours"] = e.verified_neighbours;
    merges.push_back(std::move(merge));
  }
  nlohmann::json sessions = nlohmann::json::array();
  {
    auto lock = slam.map().ReadLock();
    for (const MapSession& session : slam.map().sessions())
      sessions.push_back({{"id", session.id}, {"name", session.name}, {"source", session.source}});
  }
  return {{"count", stats.maps},    {"started", stats.maps_started}, {"merges", stats.merges},
          {"main_map", main},       {"frames_per_map", per_map},     {"unmerged_frames", unmerged},
          {"merge_events", merges}, {"sessions", sessions}};
}

nlohmann::json IntrinsicsRefinementJson(const SlamSystem& slam) {
  nlohmann::json refinements = nlohmann::json::array();
  for (const IntrinsicsRefinement& r : slam.IntrinsicsRefinements()) {
    nlohmann::json entry = {
        {"map", r.map_id},
        {"accepted", r.accepted},
        {"nominal", {{"fx", r.nominal.fx}, {"fy", r.nominal.fy}, {"cx", r.nominal.cx}, {"cy", r.nominal.cy}}},
        {"refined",
         {{"fx", r.refined.fx},
          {"fy", r.refined.fy},
          {"cx", r.refined.cx},
          {"cy", r.refined.cy},
          {"k1", r.refined.distortion.k1},
          {"k2", r.refined.distortion.k2}}},
        {"plain_cost", r.plain_cost},
        {"refined_cost", r.refined_cost}};
    if (!r.accepted) entry["reason"] = r.reason;
    refinements.push_back(std::move(entry));
  }
  return refinements;
}

void WriteFramesCsv(const std::filesystem::path& path, const SlamSystem& slam) {
  WriteFramesCsv(path, slam.AllFramePoses(), slam.MainMapId());
}

void WriteFramesCsv(const std::filesystem::path& path, const std::vector<FramePose>& poses,
                    std::uint32_t main_map) {
  std::string text = "frame,timestamp,map,source,in_main_map,tx,ty,tz,qx,qy,qz,qw\n";
  for (const FramePose& pose : poses) {
    const Rigid3d& t = pose.world_from_camera;
    text +=
        fmt::format("{},{:.6f},{},{},{},{:.6f},{:.6f},{:.6f},{:.9f},{:.9f},{:.9f},{:.9f}\n", pose.frame_index,
                    pose.timestamp, pose.map_id, pose.predicted ? "predicted" : "tracked",
                    pose.map_id == main_map ? 1 : 0, t.translation.x(), t.translation.y(), t.translation.z(),
                    t.rotation.x(), t.rotation.y(), t.rotation.z(), t.rotation.w());
  }
  WriteFileAtomically(path, text);
}

std::vector<FramePose> ReadFramesCsv(const std::filesystem::path& path) {
  TextReader reader(path);
  const std::optional<std::string> header = reader.NextLine();
  if (!header || Trim(*header) != "frame,timestamp,map,source,in_main_map,tx,ty,tz,qx,qy,qz,qw")
    throw InputError(reader.Where(), "header",
                     "expected frame,timestamp,map,source,in_main_map,tx,ty,tz,qx,qy,qz,qw");
  std::vector<FramePose> poses;
  while (const std::optional<std::string> line = reader.NextLine()) {
    if (Trim(*line).empty()) continue;
    const std::vector<std::string_view> f = SplitFields(Trim(*line), ',');
    const SourceLocation where = reader.Where();
    if (f.size() != 12)
      throw InputError(where, "record", fmt::format("expected 12 fields, found {}", f.size()));
    FramePose& p = poses.emplace_back();
    const long long frame = ParseInt(f[0], where, "frame");
    const long long map = ParseInt(f[2], where, "map");
    if (frame < 0) throw InputError(where, "frame", "must not be negative");
    if (map < 0 || map > UINT32_MAX) throw InputError(where, "map", "out of range");
    if (f[3] != "tracked" && f[3] != "predicted")
      throw InputError(where, "source", "expected tracked or predicted");
    p.frame_index = static_cast<size_t>(frame);
    p.timestamp = ParseDouble(f[1], where, "timestamp");
    p.map_id = static_cast<std::uint32_t>(map);
    p.predicted = f[3] == "predicted";
    const Eigen::Vector3d t(ParseDouble(f[5], where, "tx"), ParseDouble(f[6], where, "ty"),
                            ParseDouble(f[7], where, "tz"));
    const Eigen::Quaterniond q(ParseDouble(f[11], where, "qw"), ParseDouble(f[8], where, "qx"),
                               ParseDouble(f[9], where, "qy"), ParseDouble(f[10], where, "qz"));
    if (std::abs(q.norm() - 1.0) > 1e-3) throw InputError(where, "qx..qw", "not a unit quaternion");
    p.world_from_camera = Rigid3d(q.normalized(), t);
  }
  return poses;
}

nlohmann::json TimingJson(const TimingRegistry& timing) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [name, s] : timing.SummarizeAll()) {
    j[name] = {{"count", s.count},   {"median_ms", s.median_ms}, {"mean_ms", s.mean_ms},
               {"p95_ms", s.p95_ms}, {"max_ms", s.max_ms},       {"total_ms", s.total_ms}};
  }
  return j;
}

nlohmann::json ClassCountsJson(const ClassCounts& counts) {
  nlohmann::json j = nlohmann::json::object();
  for (int c = 0; c < kNumClasses; ++c) j[std::string(ClassKey(c))] = counts[static_cast<size_t>(c)];
  j["unlabeled"] = counts[kNumClasses];
  return j;
}

std::vector<SemanticPoint> SemanticPoints(const Map& map) {
  auto lock = map.ReadLock();
  std::vector<SemanticPoint> points;
  for (const MapPoint* p : map.MapPoints()) {
    if (!p->is_bad()) points.push_back(ToSemanticPoint(p->position(), p->labels()));
  }
  return points;
}

}  // namespace semslam
