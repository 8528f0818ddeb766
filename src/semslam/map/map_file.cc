#include "semslam/map/map_file.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <map>
#include <set>
#include <unordered_map>

#include "semslam/core/binary_io.h"
#include "semslam/core/error.h"
#include "semslam/map/map_validation.h"

namespace semslam {

// Friend of KeyFrame and MapPoint: the only code that builds them from stored state.
class MapSerializer {
 public:
  static void WriteKeyFrame(BinaryWriter& w, const KeyFrame& kf);
  // Ids as the file gives them: keyframe, point, session and map ids, each plus its offset (appending).
  struct IdOffsets {
    std::uint64_t keyframe = 0, point = 0;
    std::uint32_t session = 0, map = 0;
  };
  static std::unique_ptr<KeyFrame> ReadKeyFrame(BinaryReader& r, std::uint32_t version,
                                                const IdOffsets& offsets, std::uint64_t* parent_id,
                                                std::vector<std::uint64_t>* loop_ids);
  static void WritePoint(BinaryWriter& w, const MapPoint& p);
  // `keyframes` by the file's ids.
  static MapPoint* ReadPoint(BinaryReader& r, Map& map, const IdOffsets& offsets,
                             const std::unordered_map<std::uint64_t, KeyFrame*>& keyframes);
  static void SetParent(KeyFrame* kf, KeyFrame* parent) {
    kf->ChangeParent(parent);
    kf->first_connection_ = false;
  }
  static void AddLoopEdge(KeyFrame* kf, KeyFrame* other) { kf->AddLoopEdge(other); }
  static void SetOrigin(KeyFrame* kf) { kf->map_origin_ = true; }
};

namespace {

constexpr std::string_view kMagic("SEMSLMAP", 8);
constexpr std::uint64_t kNone = UINT64_MAX;

void WriteRigid(BinaryWriter& w, const Rigid3d& t) {
  w.Put(t.rotation.w());
  w.Put(t.rotation.x());
  w.Put(t.rotation.y());
  w.Put(t.rotation.z());
  w.Put(t.translation.x());
  w.Put(t.translation.y());
  w.Put(t.translation.z());
}

Rigid3d ReadRigid(BinaryReader& r) {
  const double qw = r.Get<double>(), qx = r.Get<double>(), qy = r.Get<double>(), qz = r.Get<double>();
  const double x = r.Get<double>(), y = r.Get<double>(), z = r.Get<double>();
  const Eigen::Quaterniond q(qw, qx, qy, qz);
  if (!std::isfinite(q.norm()) || std::abs(q.norm() - 1.0) > 1e-6 || !std::isfinite(x + y + z)) {
    r.Fail("invalid pose");
  }
  return Rigid3d(q, Eigen::Vector3d(x, y, z));
}

void WriteCamera(BinaryWriter& w, const PinholeCamera& c) {
  w.Put<std::int32_t>(c.width);
  w.Put<std::int32_t>(c.height);
  for (double v : {c.fx, c.fy, c.cx, c.cy}) w.Put(v);
}

PinholeCamera ReadCamera(BinaryReader& r) {
  PinholeCamera c;
  c.width = r.Get<std::int32_t>();
  c.height = r.Get<std::int32_t>();
  c.fx = r.Get<double>();
  c.fy = r.Get<double>();
  c.cx = r.Get<double>();
  c.cy = r.Get<double>();
  try {
    c.Check();
  } catch (const InvalidArgument& e) {
    r.Fail(e.what());
  }
  return c;
}

// A map's camera in full: size, intrinsics and the five distortion terms.
void WriteFullCamera(BinaryWriter& w, const PinholeCamera& c) {
  w.Put<std::int32_t>(c.width);
  w.Put<std::int32_t>(c.height);
  const Distortion& d = c.distortion;
  for (double v : {c.fx, c.fy, c.cx, c.cy, d.k1, d.k2, d.p1, d.p2, d.k3}) w.Put(v);
}

PinholeCamera ReadFullCamera(BinaryReader& r) {
  PinholeCamera c;
  c.width = r.Get<std::int32_t>();
  c.height = r.Get<std::int32_t>();
  for (double* v : {&c.fx, &c.fy, &c.cx, &c.cy, &c.distortion.k1, &c.distortion.k2, &c.distortion.p1,
                    &c.distortion.p2, &c.distortion.k3}) {
    *v = r.Get<double>();
  }
  constexpr int kMaxImageSide = 1 << 15;
  // Far beyond any lens PinholeCamera's undistortion converges for.
  constexpr double kMaxDistortion = 10.0;
  const Distortion& d = c.distortion;
  if (c.width <= 0 || c.height <= 0 || c.width > kMaxImageSide || c.height > kMaxImageSide) {
    r.Fail(fmt::format("camera image size {}x{} is not plausible", c.width, c.height));
  }
  if (!(std::isfinite(c.fx) && c.fx > 0 && c.fx <= 1e6 && std::isfinite(c.fy) && c.fy > 0 && c.fy <= 1e6 &&
        std::abs(c.cx) <= 4.0 * kMaxImageSide && std::abs(c.cy) <= 4.0 * kMaxImageSide)) {
    r.Fail(
        fmt::format("camera intrinsics fx={} fy={} cx={} cy={} are not plausible", c.fx, c.fy, c.cx, c.cy));
  }
  for (const double v : {d.k1, d.k2, d.p1, d.p2, d.k3}) {
    if (!(std::abs(v) <= kMaxDistortion))
      r.Fail(fmt::format("camera distortion term {} is not plausible", v));
  }
  return c;
}

bool SameCamera(const PinholeCamera& a, const PinholeCamera& b) {
  const Distortion &da = a.distortion, &db = b.distortion;
  return a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy && a.cx == b.cx &&
         a.cy == b.cy && da.k1 == db.k1 && da.k2 == db.k2 && da.p1 == db.p1 && da.p2 == db.p2 &&
         da.k3 == db.k3;
}

// Keypoint holds Eigen types (not trivially copyable): stored through a plain record.
struct StoredKeypoint {
  float x, y, angle_deg, response;
  std::int32_t level;
};

void WriteKeypoints(BinaryWriter& w, const std::vector<Keypoint>& keypoints) {
  std::vector<StoredKeypoint> stored;
  stored.reserve(keypoints.size());
  for (const Keypoint& kp : keypoints)
    stored.push_back({kp.pixel.x(), kp.pixel.y(), kp.angle_deg, kp.response, kp.level});
  w.PutVector(stored);
}

std::vector<Keypoint> ReadKeypoints(BinaryReader& r) {
  const auto stored = r.GetVector<StoredKeypoint>();
  std::vector<Keypoint> keypoints(stored.size());
  for (size_t i = 0; i < stored.size(); ++i) {
    keypoints[i].pixel = Eigen::Vector2f(stored[i].x, stored[i].y);
    keypoints[i].angle_deg = stored[i].angle_deg;
    keypoints[i].response = stored[i].response;
    keypoints[i].level = stored[i].level;
  }
  return keypoints;
}

}  // namespace

bool MapCamera::refined() const { return !SameCamera(nominal, camera); }

bool MapCamera::operator==(const MapCamera& other) const {
  return SameCamera(nominal, other.nominal) && SameCamera(camera, other.camera);
}

MapCamera KeyFrameCameraOfMap(const Map& map, std::uint32_t map_id) {
  const std::vector<KeyFrame*> keyframes = map.KeyFramesOfMap(map_id);
  Require(!keyframes.empty(), fmt::format("map {} holds no keyframe", map_id));
  return {keyframes.front()->camera(), keyframes.front()->camera()};
}

void MapSerializer::WriteKeyFrame(BinaryWriter& w, const KeyFrame& kf) {
  const FrameData& d = kf.data();
  w.Put<std::uint64_t>(kf.id());
  w.Put<std::uint64_t>(kf.frame_id());
  w.Put<double>(kf.timestamp());
  WriteRigid(w, kf.camera_from_world());
  WriteCamera(w, d.camera);
  w.Put<double>(d.stereo ? d.stereo->baseline : 0.0);
  w.Put<std::int32_t>(d.features.pyramid.num_levels);
  w.Put<float>(d.features.pyramid.scale_factor);
  w.Put<std::int32_t>(d.features.image_width);
  w.Put<std::int32_t>(d.features.image_height);
  WriteKeypoints(w, d.features.keypoints);
  w.PutVector(d.features.descriptors);
  w.PutVector(d.right_u);
  w.PutVector(d.depth);
  w.Put<std::uint64_t>(kf.parent() ? kf.parent()->id() : kNone);
  std::vector<std::uint64_t> loops;
  for (const KeyFrame* other : kf.loop_edges()) loops.push_back(other->id());
  w.PutVector(loops);
  w.Put<std::uint8_t>(kf.gps_enu.has_value());
  const Eigen::Vector3d gps = kf.gps_enu.value_or(Eigen::Vector3d::Zero());
  w.Put(gps.x());
  w.Put(gps.y());
  w.Put(gps.z());
  w.Put(kf.gps_sigma_m);
  w.PutVector(kf.keypoint_labels.quantized());
  w.PutVector(kf.keypoint_labels.labeled());
  w.Put<std::uint32_t>(kf.session());
  w.Put<std::uint32_t>(kf.map_id());
  w.Put<std::uint8_t>(kf.is_map_origin());
}

std::unique_ptr<KeyFrame> MapSerializer::ReadKeyFrame(BinaryReader& r, std::uint32_t version,
                                                      const IdOffsets& offsets, std::uint64_t* parent_id,
                                                      std::vector<std::uint64_t>* loop_ids) {
  const auto id = r.Get<std::uint64_t>();
  r.set_context(fmt::format("keyframe {}", id));
  const auto frame_id = r.Get<std::uint64_t>();
  const double timestamp = r.Get<double>();
  const Rigid3d camera_from_world = ReadRigid(r);
  const PinholeCamera camera = ReadCamera(r);
  const double baseline = r.Get<double>();
  std::optional<StereoRig> stereo;
  if (baseline > 0) stereo = StereoRig{camera, baseline};
  FeatureSet features;
  const int levels = r.Get<std::int32_t>();
  const float scale_factor = r.Get<float>();
  if (levels < 1 || levels > 32 || !(scale_factor > 1.0f && scale_factor < 4.0f)) r.Fail("invalid pyramid");
  features.pyramid = PyramidGeometry::Make(levels, scale_factor);
  features.image_width = r.Get<std::int32_t>();
  features.image_height = r.Get<std::int32_t>();
  features.keypoints = ReadKeypoints(r);
  features.descriptors = r.GetVector<Descriptor>();
  auto right_u = r.GetVector<float>();
  auto depth = r.GetVector<float>();
  const size_t n = features.keypoints.size();
  if (features.descriptors.size() != n || (!right_u.empty() && right_u.size() != n) ||
      (!depth.empty() && depth.size() != n)) {
    r.Fail("feature arrays of different lengths");
  }
  for (const auto& kp : features.keypoints) {
    if (kp.level < 0 || kp.level >= levels || !kp.pixel.allFinite()) r.Fail("invalid keypoint");
  }
  *parent_id = r.Get<std::uint64_t>();
  *loop_ids = r.GetVector<std::uint64_t>();
  const bool has_gps = r.Get<std::uint8_t>() != 0;
  Eigen::Vector3d gps;
  gps.x() = r.Get<double>();
  gps.y() = r.Get<double>();
  gps.z() = r.Get<double>();
  const double gps_sigma = r.Get<double>();
  auto quantized_labels = r.GetVector<std::uint8_t>();
  auto labeled = r.GetVector<std::uint8_t>();
  if (!labeled.empty() && (labeled.size() != n || quantized_labels.size() != n * kNumClasses)) {
    r.Fail("keypoint labels of the wrong size");
  }
  std::uint32_t session = 0, map_id = 0;
  bool origin = false;
  if (version >= 2) {
    session = r.Get<std::uint32_t>();
    map_id = r.Get<std::uint32_t>();
    const auto origin_byte = r.Get<std::uint8_t>();
    if (origin_byte > 1) r.Fail("invalid map origin flag");
    origin = origin_byte == 1;
  }

  std::optional<Eigen::Vector3d> gps_enu;
  if (has_gps) gps_enu = gps;
  CheckKeyFrameRecord({id, timestamp, &camera, baseline, features.image_width, features.image_height,
                       &features.keypoints, &right_u, &depth, gps_enu, gps_sigma},
                      r.file());
  Frame frame(frame_id, timestamp,
              MakeFrameData(camera, stereo, std::move(features), std::move(right_u), std::move(depth)));
  frame.SetPose(camera_from_world);
  auto kf = std::make_unique<KeyFrame>(id + offsets.keyframe, frame);
  if (has_gps) kf->gps_enu = gps;
  kf->gps_sigma_m = gps_sigma;
  kf->keypoint_labels.Restore(std::move(quantized_labels), std::move(labeled));
  kf->session_ = session + offsets.session;
  kf->map_id_ = map_id + offsets.map;
  kf->map_origin_ = origin;
  return kf;
}

void MapSerializer::WritePoint(BinaryWriter& w, const MapPoint& p) {
  w.Put<std::uint64_t>(p.id());
  w.Put<std::uint64_t>(p.reference_keyframe() ? p.reference_keyframe()->id() : kNone);
  w.Put(p.position().x());
  w.Put(p.position().y());
  w.Put(p.position().z());
  w.Put<std::int32_t>(p.visible());
  w.Put<std::int32_t>(p.found());
  p.labels().AppendTo(w);
  std::vector<std::uint64_t> observations;
  for (const auto& [kf, index] : p.observations()) {
    observations.push_back(kf->id());
    observations.push_back(static_cast<std::uint64_t>(index));
  }
  w.PutVector(observations);
}

MapPoint* MapSerializer::ReadPoint(BinaryReader& r, Map& map, const IdOffsets& offsets,
                                   const std::unordered_map<std::uint64_t, KeyFrame*>& keyframes) {
  const auto id = r.Get<std::uint64_t>();
  r.set_context(fmt::format("map point {}", id));
  const auto reference_id = r.Get<std::uint64_t>();
  Eigen::Vector3d position;
  position.x() = r.Get<double>();
  position.y() = r.Get<double>();
  position.z() = r.Get<double>();
  if (!position.allFinite()) r.Fail("position is not finite");
  const int visible = r.Get<std::int32_t>();
  const int found = r.Get<std::int32_t>();
  CheckPointRecord(id, position, visible, found, r.file());
  const LabelDistribution labels = LabelDistribution::ReadFrom(r);
  const auto observations = r.GetVector<std::uint64_t>();
  if (observations.size() % 2 != 0) r.Fail("odd observation list");

  const auto ref = keyframes.find(reference_id);
  if (ref == keyframes.end()) r.Fail(fmt::format("reference keyframe {} does not exist", reference_id));
  auto point = std::make_unique<MapPoint>(id + offsets.point, position, ref->second);
  point->visible_ = visible;
  point->found_ = found;
  point->labels_ = labels;
  MapPoint* p = map.RestoreMapPoint(std::move(point));
  for (size_t i = 0; i < observations.size(); i += 2) {
    const auto kf = keyframes.find(observations[i]);
    if (kf == keyframes.end()) r.Fail(fmt::format("observing keyframe {} does not exist", observations[i]));
    const auto index = observations[i + 1];
    if (index >= kf->second->num_features()) r.Fail("observation index out of range");
    kf->second->SetMapPoint(static_cast<int>(index), p);
    p->AddObservation(kf->second, static_cast<int>(index), /*fuse_labels=*/false);
  }
  if (p->observations().empty()) r.Fail("point without observations");
  p->first_keyframe_id_ = p->observations().begin()->first->id();
  return p;
}

void WriteMapFile(const std::filesystem::path& path, const Map& map, const MapFileContents& extra) {
  ChecksummedFileWriter file(path, kMagic, kMapFileVersion);
  BinaryWriter& w = file.payload();
  w.Put<std::uint32_t>(static_cast<std::uint32_t>(map.sessions().size()));
  for (const MapSession& session : map.sessions()) {
    w.PutString(session.name);
    w.PutString(session.source);
  }
  w.Put<std::uint32_t>(map.active_map_id());
  w.Put<std::uint32_t>(map.next_map_id());
  const std::vector<std::uint32_t> map_ids = map.MapIds();
  w.Put<std::uint32_t>(static_cast<std::uint32_t>(map_ids.size()));
  for (const std::uint32_t map_id : map_ids) {
    const auto it = extra.cameras.find(map_id);
    const MapCamera camera = it != extra.cameras.end() ? it->second : KeyFrameCameraOfMap(map, map_id);
    w.Put<std::uint32_t>(map_id);
    WriteFullCamera(w, camera.nominal);
    WriteFullCamera(w, camera.camera);
  }
  const auto keyframes = map.KeyFrames();
  const auto points = map.MapPoints();
  w.Put<std::uint64_t>(keyframes.size());
  for (const KeyFrame* kf : keyframes) MapSerializer::WriteKeyFrame(w, *kf);
  std::uint64_t good_points = 0;
  for (const MapPoint* p : points) good_points += !p->is_bad() && !p->observations().empty();
  w.Put<std::uint64_t>(good_points);
  for (const MapPoint* p : points) {
    if (!p->is_bad() && !p->observations().empty()) MapSerializer::WritePoint(w, *p);
  }
  w.Put<std::uint64_t>(extra.extra_sections.size());
  for (const auto& [name, bytes] : extra.extra_sections) {
    w.PutString(name);
    w.PutString(bytes);
  }
  file.Commit();
}

namespace {

// Reads `path` into `map`: into an empty one as the file has it, or appended to a map that holds keyframes
// already (every id of the file moved past the map's own; its sessions after the map's).
MapFileContents ReadIntoMap(const std::filesystem::path& path, Map& map, bool append) {
  const ChecksummedFile file = ReadChecksummedFile(path, kMagic);
  if (file.version < 1 || file.version > kMapFileVersion) {
    throw InputError(path, fmt::format("map file version {} is not supported (this build reads 1 to {})",
                                       file.version, kMapFileVersion));
  }
  Require(append || map.NumKeyFrames() == 0, "ReadMapFile needs an empty map");
  MapSerializer::IdOffsets offsets;
  if (append && map.NumKeyFrames() > 0) {
    offsets.keyframe = map.next_keyframe_id();
    offsets.point = map.next_point_id();
    offsets.session = static_cast<std::uint32_t>(map.sessions().size());
    offsets.map = map.next_map_id();
  } else {
    append = false;
  }
  BinaryReader r(file.payload, path);
  std::vector<MapSession> sessions = {MapSession{}};
  std::uint32_t active_map = 0, next_map = 1;
  if (file.version >= 2) {
    r.set_context("sessions");
    const auto num_sessions = r.Get<std::uint32_t>();
    if (num_sessions == 0 || num_sessions > 1'000'000) r.Fail("invalid session count");
    sessions.clear();
    for (std::uint32_t i = 0; i < num_sessions; ++i) {
      MapSession session;
      session.id = i;
      session.name = r.GetString();
      session.source = r.GetString();
      sessions.push_back(std::move(session));
    }
    active_map = r.Get<std::uint32_t>();
    next_map = r.Get<std::uint32_t>();
    if (active_map >= next_map) r.Fail("the active map id is not below the next map id");
  }
  std::map<std::uint32_t, MapCamera> cameras;
  if (file.version >= 3) {
    r.set_context("map cameras");
    const auto num_cameras = r.Get<std::uint32_t>();
    if (num_cameras > next_map) r.Fail("more cameras than maps");
    for (std::uint32_t i = 0; i < num_cameras; ++i) {
      const auto map_id = r.Get<std::uint32_t>();
      r.set_context(fmt::format("camera of map {}", map_id));
      if (map_id >= next_map) r.Fail("the map id is out of range");
      if (!cameras.empty() && map_id + offsets.map <= cameras.rbegin()->first)
        r.Fail("the maps are not in id order");
      MapCamera camera;
      camera.nominal = ReadFullCamera(r);
      camera.camera = ReadFullCamera(r);
      if (camera.camera.width != camera.nominal.width || camera.camera.height != camera.nominal.height)
        r.Fail("the camera and the nominal one have images of different sizes");
      cameras[map_id + offsets.map] = camera;
    }
  }
  const auto num_keyframes = r.Get<std::uint64_t>();
  std::unordered_map<std::uint64_t, KeyFrame*> by_file_id;
  std::vector<KeyFrame*> keyframes;                                         // read, in the file's (id) order
  std::vector<std::pair<std::uint64_t, std::vector<std::uint64_t>>> links;  // by the file's ids
  std::uint64_t last_id = 0;
  for (std::uint64_t i = 0; i < num_keyframes; ++i) {
    std::uint64_t parent = kNone;
    std::vector<std::uint64_t> loops;
    auto kf = MapSerializer::ReadKeyFrame(r, file.version, offsets, &parent, &loops);
    const std::uint64_t file_id = kf->id() - offsets.keyframe;
    if (kf->session() - offsets.session >= sessions.size())
      r.Fail(fmt::format("session {} does not exist", kf->session() - offsets.session));
    if (kf->map_id() - offsets.map >= next_map)
      r.Fail(fmt::format("map id {} is out of range", kf->map_id() - offsets.map));
    if (by_file_id.count(file_id)) r.Fail(fmt::format("duplicate keyframe id {}", file_id));
    // Written in id order; the links below are matched to keyframes by that order.
    if (!links.empty() && file_id < last_id) r.Fail("keyframes are not in id order");
    last_id = file_id;
    KeyFrame* k = map.RestoreKeyFrame(std::move(kf));
    by_file_id[file_id] = k;
    keyframes.push_back(k);
    links.emplace_back(parent, std::move(loops));
  }
  const auto num_points = r.Get<std::uint64_t>();
  std::vector<MapPoint*> points;  // not reserved: the count is the file's, checked only as points are read
  for (std::uint64_t i = 0; i < num_points; ++i)
    points.push_back(MapSerializer::ReadPoint(r, map, offsets, by_file_id));
  MapFileContents contents;
  contents.first_session = offsets.session;
  contents.first_map_id = offsets.map;
  r.set_context("extra sections");
  const auto num_extra = r.Get<std::uint64_t>();
  for (std::uint64_t i = 0; i < num_extra; ++i) {
    std::string name = r.GetString();
    contents.extra_sections[name] = r.GetString();
  }
  if (!r.AtEnd()) r.Fail("trailing bytes");

  if (append) {
    std::vector<MapSession> all = map.sessions();
    for (MapSession& session : sessions) {
      session.id += offsets.session;
      all.push_back(std::move(session));
    }
    map.RestoreSessions(std::move(all));
    map.RestoreMapIds(map.active_map_id(), offsets.map + next_map);
  } else {
    map.RestoreSessions(std::move(sessions));
    map.RestoreMapIds(active_map, next_map);
  }
  // Older files, and maps the file has no camera for: the keyframes' own camera, as they were fitted to it.
  std::set<std::uint32_t> map_ids;
  for (const KeyFrame* kf : keyframes) map_ids.insert(kf->map_id());
  for (const std::uint32_t map_id : map_ids) {
    const auto it = cameras.find(map_id);
    contents.cameras[map_id] = it != cameras.end() ? it->second : KeyFrameCameraOfMap(map, map_id);
  }
  // Derived state: covisibility, spanning tree, loop edges, point normals and descriptors.
  if (file.version == 1 && !keyframes.empty()) MapSerializer::SetOrigin(keyframes.front());
  std::unordered_map<std::uint64_t, std::uint64_t> parent_of;  // by the file's ids
  for (size_t i = 0; i < keyframes.size(); ++i) {
    const std::uint64_t file_id = keyframes[i]->id() - offsets.keyframe;
    parent_of[file_id] = links[i].first == kNone ? kNoParent : links[i].first;
    for (const auto loop : links[i].second) {
      if (loop == file_id) throw InputError(path, fmt::format("keyframe {}: loop edge to itself", loop));
    }
  }
  for (const std::uint64_t id : RepairSpanningTree(parent_of, path)) {
    spdlog::warn(
        "{}: keyframe {} was its own ancestor in the spanning tree (a map file of a semslam before "
        "2026-11-28); it is made a root",
        path.string(), id);
  }
  // The stored tree first: UpdateConnections would otherwise choose parents of its own.
  for (KeyFrame* kf : keyframes) {
    const std::uint64_t parent = parent_of.at(kf->id() - offsets.keyframe);
    MapSerializer::SetParent(kf, parent == kNoParent ? nullptr : by_file_id.at(parent));
  }
  for (size_t i = 0; i < keyframes.size(); ++i) {
    KeyFrame* kf = keyframes[i];
    kf->UpdateConnections();
    for (const auto loop : links[i].second) {
      const auto it = by_file_id.find(loop);
      if (it == by_file_id.end())
        throw InputError(
            path, fmt::format("keyframe {}: loop edge to missing {}", kf->id() - offsets.keyframe, loop));
      MapSerializer::AddLoopEdge(kf, it->second);
    }
  }
  for (MapPoint* p : points) {
    p->UpdateNormalAndDepth();
    p->UpdateDescriptor();
  }
  return contents;
}

}  // namespace

MapFileContents ReadMapFile(const std::filesystem::path& path, Map& map) {
  return ReadIntoMap(path, map, /*append=*/false);
}

MapFileContents AppendMapFile(const std::filesystem::path& path, Map& map) {
  return ReadIntoMap(path, map, /*append=*/true);
}

}  // namespace semslam
