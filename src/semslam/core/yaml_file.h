#pragma once
// Loading YAML input (SLAM configuration, camera files, model cards) with located errors. yaml-cpp accepts a
// mapping that repeats a key and then silently uses one of the values; these loaders refuse it instead,
// naming the line of the repeated key.

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <string>

#include "semslam/core/error.h"

namespace semslam {

// The location of a node's mark in `file` (line 0 when yaml-cpp does not know it).
SourceLocation YamlLocation(const std::filesystem::path& file, const YAML::Mark& mark);

// Parses `file`. Throws InputError naming the file (and the line) when it cannot be read, is not YAML, holds
// text that is not UTF-8, repeats a key in a mapping, or has a key that is not a plain name.
YAML::Node LoadYamlFile(const std::filesystem::path& file);
// The same for text read elsewhere; `source` names it in errors.
YAML::Node LoadYamlText(const std::string& text, const std::filesystem::path& source);

// Throws InputError at the second occurrence of a key repeated in any mapping under `node`.
void RequireUniqueYamlKeys(const YAML::Node& node, const std::filesystem::path& source);

}  // namespace semslam
