#include "semslam/system/slam_config.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cctype>
#include <functional>
#include <map>
#include <string_view>

#include "semslam/core/error.h"
#include "semslam/core/yaml_file.h"

namespace semslam {
namespace {

// One configurable option: how to read it from a node and how to print it.
struct Field {
  std::function<void(const YAML::Node&)> read;
  std::function<void(YAML::Emitter&)> write;
};
using Section = std::map<std::string, Field>;

template <typename T>
Field Bind(T* value) {
  return {[value](const YAML::Node& node) { *value = node.as<T>(); },
          [value](YAML::Emitter& out) { out << *value; }};
}

Field BindPacing(Pacing* pacing) {
  return {[pacing](const YAML::Node& node) {
            const auto parsed = ParsePacing(node.as<std::string>());
            if (!parsed) throw YAML::Exception(node.Mark(), "expected fast, realtime or synchronous");
            *pacing = *parsed;
          },
          [pacing](YAML::Emitter& out) { out << std::string(PacingName(*pacing)); }};
}

Field BindPath(std::filesystem::path* path) {
  return {[path](const YAML::Node& node) { *path = node.as<std::string>(); },
          [path](YAML::Emitter& out) { out << path->string(); }};
}

// Keys an earlier version read, with what replaced them: an old configuration file is told what to write.
const std::map<std::string, std::string>& RenamedKeys() {
  static const std::map<std::string, std::string> renamed = {
      {"tracking.max_frames_between_keyframes",
       "tracking.max_seconds_between_keyframes (in seconds: 10 frames at 10 Hz are 1.0)"},
      {"tracking.min_frames_between_keyframes",
       "tracking.min_seconds_between_keyframes (in seconds: 3 frames at 10 Hz are 0.3)"},
  };
  return renamed;
}

std::map<std::string, Section> Sections(SlamOptions* o) {
  std::map<std::string, Section> s;
  s["features"] = {
      {"num_features", Bind(&o->tracker.orb.num_features)},
      {"init_num_features", Bind(&o->tracker.init_num_features)},
      {"init_level_share_exponent", Bind(&o->tracker.init_level_share_exponent)},
      {"num_levels", Bind(&o->tracker.orb.num_levels)},
      {"scale_factor", Bind(&o->tracker.orb.scale_factor)},
      {"initial_fast_threshold", Bind(&o->tracker.orb.initial_fast_threshold)},
      {"min_fast_threshold", Bind(&o->tracker.orb.min_fast_threshold)},
      {"level_share_exponent", Bind(&o->tracker.orb.level_share_exponent)},
  };
  s["tracking"] = {
      {"max_seconds_between_keyframes", Bind(&o->tracker.max_seconds_between_keyframes)},
      {"min_seconds_between_keyframes", Bind(&o->tracker.min_seconds_between_keyframes)},
      {"keyframe_tracked_ratio_mono", Bind(&o->tracker.keyframe_tracked_ratio_mono)},
      {"keyframe_tracked_ratio_stereo", Bind(&o->tracker.keyframe_tracked_ratio_stereo)},
      {"keyframe_collapse_ratio_mono", Bind(&o->tracker.keyframe_collapse_ratio_mono)},
      {"keyframe_collapse_ratio_stereo", Bind(&o->tracker.keyframe_collapse_ratio_stereo)},
      {"keyframe_weak_inliers_mono", Bind(&o->tracker.keyframe_weak_inliers_mono)},
      {"motion_model_min_kept_ratio", Bind(&o->tracker.motion_model_min_kept_ratio)},
      {"close_depth_baselines", Bind(&o->tracker.close_depth_baselines)},
      {"init_min_matches", Bind(&o->tracker.init_min_matches)},
      {"init_match_max_level", Bind(&o->tracker.init_match_max_level)},
      {"init_match_level_difference", Bind(&o->tracker.init_match_level_difference)},
      {"init_min_parallax_deg", Bind(&o->tracker.init_min_parallax_deg)},
      {"init_parallax_rank", Bind(&o->tracker.init_parallax_rank)},
      {"init_min_points", Bind(&o->tracker.init_min_points)},
      {"relocalization_timeout_s", Bind(&o->tracker.relocalization_timeout_s)},
      {"min_keyframes_to_keep_map", Bind(&o->tracker.min_keyframes_to_keep_map)},
      {"pacing", BindPacing(&o->pacing)},
  };
  s["mapping"] = {
      {"triangulation_neighbours_mono", Bind(&o->mapper.triangulation_neighbours_mono)},
      {"triangulation_neighbours_stereo", Bind(&o->mapper.triangulation_neighbours_stereo)},
      {"redundant_keyframe_ratio", Bind(&o->mapper.redundant_keyframe_ratio)},
      {"local_ba_iterations", Bind(&o->mapper.local_ba_iterations)},
      {"min_parallax_deg", Bind(&o->mapper.min_parallax_deg)},
      {"final_global_ba", Bind(&o->final_global_ba)},
      {"final_refine_intrinsics", Bind(&o->final_refine_intrinsics)},
      {"final_refine_intrinsics_min_reduction", Bind(&o->final_refine_intrinsics_min_reduction)},
      {"final_refine_intrinsics_min_keyframes", Bind(&o->final_refine_intrinsics_min_keyframes)},
      {"max_queued_keyframes", Bind(&o->max_queued_keyframes)},
      {"realtime_wait_for_mapping_frames", Bind(&o->realtime_wait_for_mapping_frames)},
      {"final_global_ba_iterations", Bind(&o->final_global_ba_iterations)},
      {"final_global_ba_refine_iterations", Bind(&o->final_global_ba_refine_iterations)},
  };
  s["loop"] = {
      {"enabled", Bind(&o->loop.enabled)},
      {"consistency_threshold", Bind(&o->loop.consistency_threshold)},
      {"min_keyframes_between_loops", Bind(&o->loop.min_keyframes_between_loops)},
      {"min_bow_matches", Bind(&o->loop.min_bow_matches)},
      {"min_sim3_inliers", Bind(&o->loop.min_sim3_inliers)},
      {"min_projected_matches", Bind(&o->loop.min_projected_matches)},
      {"min_verified_neighbours", Bind(&o->loop.min_verified_neighbours)},
      {"verification_matches", Bind(&o->loop.verification_matches)},
      {"max_depth_ratio", Bind(&o->loop.max_depth_ratio)},
      {"max_refined_depth_ratio", Bind(&o->loop.max_refined_depth_ratio)},
      {"max_stereo_correction_ratio", Bind(&o->loop.max_stereo_correction_ratio)},
      {"stereo_correction_slack_m", Bind(&o->loop.stereo_correction_slack_m)},
      {"stereo_rotation_slack_deg", Bind(&o->loop.stereo_rotation_slack_deg)},
      {"max_stereo_rotation_deg_per_100m", Bind(&o->loop.max_stereo_rotation_deg_per_100m)},
      {"max_mono_correction_ratio", Bind(&o->loop.max_mono_correction_ratio)},
      {"mono_correction_slack_depths", Bind(&o->loop.mono_correction_slack_depths)},
      {"max_mono_loop_rotation_deg", Bind(&o->loop.max_mono_loop_rotation_deg)},
      {"merge_maps", Bind(&o->loop.merge_maps)},
      {"global_ba", Bind(&o->loop.global_ba)},
      {"global_ba_iterations", Bind(&o->loop.global_ba_iterations)},
      {"global_ba_window_keyframes", Bind(&o->loop.global_ba_window_keyframes)},
  };
  s["place"] = {
      {"vocabulary", BindPath(&o->vocabulary)},
  };
  return s;
}

SourceLocation Where(const std::filesystem::path& file, const YAML::Mark& mark) {
  return {file, mark.line >= 0 ? mark.line + 1 : 0};
}

// Whether `word` occurs in `text` as a whole identifier (not as part of a longer one).
bool NamesWord(std::string_view text, std::string_view word) {
  const auto identifier = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
  for (size_t at = text.find(word); at != std::string_view::npos; at = text.find(word, at + 1)) {
    const size_t end = at + word.size();
    if ((at == 0 || !identifier(text[at - 1])) && (end == text.size() || !identifier(text[end]))) return true;
  }
  return false;
}

// A map starts from init_min_matches matches between two frames: fewer features than that per frame and no
// run could ever start one (it would track nothing, silently).
void CheckFeatureBudget(const SlamOptions& o, const std::filesystem::path& file,
                        const std::map<std::string, int>& lines) {
  const auto where = [&](const std::string& field) {
    const auto it = lines.find(field);
    return SourceLocation{file, it == lines.end() ? 0 : it->second};
  };
  const int init_features =
      o.tracker.init_num_features > 0 ? o.tracker.init_num_features : 2 * o.tracker.orb.num_features;
  if (o.tracker.orb.num_features < o.tracker.init_min_matches) {
    throw InputError(where("features.num_features"), "features.num_features",
                     fmt::format("{} features per frame are fewer than the {} matches a map needs to start "
                                 "(tracking.init_min_matches): no map could be made",
                                 o.tracker.orb.num_features, o.tracker.init_min_matches));
  }
  if (init_features < o.tracker.init_min_matches) {
    throw InputError(
        where("features.init_num_features"), "features.init_num_features",
        fmt::format("{} features for initialization are fewer than the {} matches a map needs to "
                    "start (tracking.init_min_matches)",
                    init_features, o.tracker.init_min_matches));
  }
}

}  // namespace

void ApplySlamConfig(const std::filesystem::path& file, SlamOptions* options) {
  const YAML::Node root = LoadYamlFile(file);
  if (root.IsNull()) return;  // an empty file changes nothing
  if (!root.IsMap())
    throw InputError(Where(file, root.Mark()), "the configuration must be a map of sections");
  SlamOptions updated = *options;
  auto sections = Sections(&updated);
  std::map<std::string, int> lines;  // "section.key" -> line, for the checks across keys below
  for (const auto& entry : root) {
    const std::string section_name = entry.first.as<std::string>();
    const auto section = sections.find(section_name);
    if (section == sections.end()) {
      throw InputError(Where(file, entry.first.Mark()), section_name,
                       "unknown section (expected features, tracking, mapping, loop or place)");
    }
    if (!entry.second.IsMap())
      throw InputError(Where(file, entry.second.Mark()), section_name, "must be a map");
    for (const auto& item : entry.second) {
      const std::string key = item.first.as<std::string>();
      const std::string field = section_name + "." + key;
      const auto it = section->second.find(key);
      if (it == section->second.end()) {
        const auto renamed = RenamedKeys().find(field);
        throw InputError(Where(file, item.first.Mark()), field,
                         renamed == RenamedKeys().end()
                             ? std::string("unknown key")
                             : fmt::format("unknown key: now {}", renamed->second));
      }
      lines[field] = item.first.Mark().line + 1;
      try {
        it->second.read(item.second);
      } catch (const YAML::Exception& e) {
        throw InputError(Where(file, item.second.Mark()), field, fmt::format("bad value: {}", e.msg));
      }
    }
  }
  try {
    updated.tracker.Check();
    updated.mapper.Check();
    updated.loop.Check();
  } catch (const InvalidArgument& e) {
    // The options' checks name their field; the key of that name in this file gives the line.
    const std::string message = e.what();
    for (const auto& [field, line] : lines) {
      if (NamesWord(message, field.substr(field.find('.') + 1))) {
        throw InputError(SourceLocation{file, line}, field, message);
      }
    }
    throw InputError(file, message);
  }
  CheckFeatureBudget(updated, file, lines);
  *options = updated;
}

std::string SlamConfigToYaml(const SlamOptions& options) {
  SlamOptions copy = options;
  YAML::Emitter out;
  out << YAML::BeginMap;
  for (auto& [section_name, fields] : Sections(&copy)) {
    out << YAML::Key << section_name << YAML::Value << YAML::BeginMap;
    for (auto& [key, field] : fields) {
      out << YAML::Key << key << YAML::Value;
      field.write(out);
    }
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

}  // namespace semslam
