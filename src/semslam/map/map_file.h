#pragma once
// The reusable map file (`map.semslam`): a versioned binary file with a checksum, written atomically.
// It holds the sessions (drives) that made the map, every keyframe (session, map of the atlas, pose,
// features, stereo, spanning tree, loop edges, GPS link, per-keypoint labels) and every map point (position,
// observations, label distribution), the camera of each map of the atlas, plus named extra sections that
// other parts store opaquely (GPS alignment, landmarks, topology, ...). Version 1 files (one session, one
// map) and version 2 files (no cameras of their own: each map's is its keyframes') are read too. Bag-of-words
// vectors are not stored: they are recomputed with the vocabulary on load.

#include <filesystem>
#include <map>
#include <string>

#include "semslam/map/map.h"

namespace semslam {

// The camera of one map of the atlas: the calibration of the sensor that made it, as its sequence gave it,
// and the camera its poses and points were fitted to, which frames tracked against the map are undistorted
// with. The two differ when the final bundle adjustment refined the intrinsics (mapping/map_optimization.h):
// `camera` then has the refined focal length, principal point and radial terms, and the map's keyframes carry
// its ideal pinhole (their keypoints undistorted with it).
struct MapCamera {
  PinholeCamera nominal;
  PinholeCamera camera;

  // Whether `camera` is not the nominal one (exactly).
  bool refined() const;
  bool operator==(const MapCamera& other) const;
};

struct MapFileContents {
  // Named extra sections (e.g. "geo.alignment", "landmarks"), each an opaque string (JSON by convention).
  std::map<std::string, std::string> extra_sections;
  // By map id. WriteMapFile writes one per map holding keyframes, from here or, for a map missing here, its
  // first keyframe's camera as both; ReadMapFile gives one per map holding keyframes.
  std::map<std::uint32_t, MapCamera> cameras;
  // AppendMapFile: where the file's ids went in the map (its session s is now first_session + s, its map m
  // first_map_id + m). 0 for ReadMapFile.
  std::uint32_t first_session = 0;
  std::uint32_t first_map_id = 0;
};

// Writes the whole map (call with at least a read lock held).
void WriteMapFile(const std::filesystem::path& path, const Map& map, const MapFileContents& extra = {});

// Reads a map file into an empty `map`; restores covisibility, normals and descriptors. Throws InputError
// naming the file on a wrong magic, unsupported version, checksum mismatch, truncation or inconsistent
// references.
MapFileContents ReadMapFile(const std::filesystem::path& path, Map& map);
// Reads a map file into a map that may hold others already (sessions of one atlas): every keyframe, point,
// session and map id of the file is moved past the map's own; `cameras` are by the new map ids. Into an
// empty map it reads as ReadMapFile. Throws as ReadMapFile.
MapFileContents AppendMapFile(const std::filesystem::path& path, Map& map);

// The camera a map without a stored one has: its first keyframe's (ideal pinhole) as both. Read lock.
MapCamera KeyFrameCameraOfMap(const Map& map, std::uint32_t map_id);

// 3: each map's camera (MapCamera). 2: sessions and maps of the atlas. 1: one map.
inline constexpr std::uint32_t kMapFileVersion = 3;

}  // namespace semslam
