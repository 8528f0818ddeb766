#pragma once
// Reading back what a synthetic-city dataset was made from: scene.json's options rebuild the same town and
// drive (SyntheticCity is deterministic), so evaluations can ask the scene itself (classes of surfaces,
// landmarks, true poses) instead of parsing every surface from the file.

#include <filesystem>
#include <optional>

#include "semslam/sim/synthetic_city.h"

namespace semslam::sim {

// The options stored in DIR/scene.json. Throws InputError naming the file and field when it is malformed.
SynthOptions ReadSceneOptions(const std::filesystem::path& scene_json);

// The scene.json of a dataset, given the dataset folder, its sequences/XX folder or anything below; nullopt
// when there is none (not a synthetic-city dataset).
std::optional<std::filesystem::path> FindSceneJson(const std::filesystem::path& sequence_dir);

}  // namespace semslam::sim
