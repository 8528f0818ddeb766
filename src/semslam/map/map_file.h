#pragma once
// The reusable map file (`map.semslam`): a versioned binary file with a checksum, written atomically.
// It holds the sessions (drives) that made the map, every keyframe (session, map of the atlas, pose,
// features, stereo, spanning tree, loop edges, GPS link, per-keypoint labels) and every map point (position,
// observations, label distribution), plus named extra sections that other parts store opaquely (GPS
// alignment, landmarks, topology, ...). Version 1 files (one session, one map) are read too.
// Bag-of-words vectors are not stored: they are recomputed with the vocabulary on load.

#include <filesystem>
#include <map>
#include <string>

#include "semslam/map/map.h"

namespace semslam {

struct MapFileContents {
  // Named extra sections (e.g. "geo.alignment", "landmarks"), each an opaque string (JSON by convention).
  std::map<std::string, std::string> extra_sections;
};

// Writes the whole map (call with at least a read lock held).
void WriteMapFile(const std::filesystem::path& path, const Map& map, const MapFileContents& extra = {});

// Reads a map file into an empty `map`; restores covisibility, normals and descriptors. Throws InputError
// naming the file on a wrong magic, unsupported version, checksum mismatch, truncation or inconsistent
// references.
MapFileContents ReadMapFile(const std::filesystem::path& path, Map& map);

inline constexpr std::uint32_t kMapFileVersion = 2;

}  // namespace semslam
