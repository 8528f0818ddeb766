#pragma once
// The georeference as JSON (for the map file's extra sections, so that `semslam localize` places a
// relocalized camera in WGS84 as the mapping run did): origin, global enu_from_map, and the local
// corrections.

#include <filesystem>
#include <string>

#include "semslam/geo/georeference.h"

namespace semslam {

std::string GeoreferenceToJson(const Georeference& georeference);
// Throws InputError naming `source` and the field on malformed text.
Georeference GeoreferenceFromJson(const std::string& text, const std::filesystem::path& source);

}  // namespace semslam
