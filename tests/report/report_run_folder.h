#pragma once
// A made-up run folder holding every input the HTML report reads, and its parts, for the report's tests.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string_view>
#include <vector>

#include "semslam/geometry/trajectory.h"
#include "semslam/semantics/semantic_outputs.h"

namespace semslam::report_test {

// A landmark name that must come out escaped in every part of the page.
inline constexpr std::string_view kTrickyName = "Caf\xC3\xA9 </script><b>&";

nlohmann::json RunJson();
nlohmann::json TimingJson();
std::vector<SemanticPoint> MapPoints(int count);
Trajectory Poses(int count);
nlohmann::json LandmarksGeoJson();
nlohmann::json ObjectsJson();
void WriteJson(const std::filesystem::path& file, const nlohmann::json& value);
// A run folder with every input the report reads.
void WriteFullRun(const std::filesystem::path& dir, int points = 5000, int poses = 100);

}  // namespace semslam::report_test
