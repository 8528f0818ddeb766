#include "semslam/system/atlas_outputs.h"

#include <fmt/format.h>

#include <map>
#include <nlohmann/json.hpp>

#include "semslam/core/atomic_file.h"

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
  const std::uint32_t main = slam.MainMapId();
  std::string text = "frame,timestamp,map,source,in_main_map,tx,ty,tz,qx,qy,qz,qw\n";
  for (const FramePose& pose : slam.AllFramePoses()) {
    const Rigid3d& t = pose.world_from_camera;
    text +=
        fmt::format("{},{:.6f},{},{},{},{:.6f},{:.6f},{:.6f},{:.9f},{:.9f},{:.9f},{:.9f}\n", pose.frame_index,
                    pose.timestamp, pose.map_id, pose.predicted ? "predicted" : "tracked",
                    pose.map_id == main ? 1 : 0, t.translation.x(), t.translation.y(), t.translation.z(),
                    t.rotation.x(), t.rotation.y(), t.rotation.z(), t.rotation.w());
  }
  WriteFileAtomically(path, text);
}

}  // namespace semslam
