#include "semslam/io/image_folder.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <set>
#include <system_error>

#include "semslam/core/atomic_file.h"
#include "semslam/core/error.h"
#include "semslam/core/yaml_file.h"
#include "semslam/io/sequence_internal.h"
#include "semslam/io/trajectory_io.h"

namespace semslam {

namespace fs = std::filesystem;

namespace {

constexpr double kDefaultFps = 10.0;

const std::set<std::string>& KnownKeys() {
  static const std::set<std::string> keys = {"fx",     "fy",           "cx",           "cy",     "width",
                                             "height", "k1",           "k2",           "p1",     "p2",
                                             "k3",     "baseline",     "right_images", "images", "fps",
                                             "times",  "ground_truth", "labels",       "depth",  "name"};
  return keys;
}

std::string KnownKeyList() {
  std::string list;
  for (const std::string& key : KnownKeys()) list += (list.empty() ? "" : ", ") + key;
  return list;
}

class YamlMap {
 public:
  YamlMap(const fs::path& file, const YAML::Node& root) : file_(file), root_(root) {}

  SourceLocation Where(const YAML::Node& node) const {
    const YAML::Mark mark = node.Mark();
    return {file_, mark.is_null() ? 0 : mark.line + 1};
  }
  SourceLocation Where(const std::string& key) const { return Where(root_[key]); }
  bool Has(const std::string& key) const { return static_cast<bool>(root_[key]); }

  std::optional<double> Double(const std::string& key) const {
    const YAML::Node node = root_[key];
    if (!node) return std::nullopt;
    double value = 0;
    try {
      if (!node.IsScalar()) throw YAML::Exception(node.Mark(), "not a scalar");
      value = node.as<double>();
    } catch (const YAML::Exception&) {
      throw InputError(Where(node), key, "expected a number");
    }
    if (!std::isfinite(value)) throw InputError(Where(node), key, "must be finite");
    return value;
  }
  double RequiredDouble(const std::string& key) const {
    const auto value = Double(key);
    if (!value) throw InputError(SourceLocation{file_, 0}, key, "missing (required)");
    return *value;
  }
  std::optional<int> Int(const std::string& key) const {
    const auto value = Double(key);
    if (!value) return std::nullopt;
    if (*value != std::floor(*value) || std::abs(*value) > 1e9) {
      throw InputError(Where(key), key, "expected an integer");
    }
    return static_cast<int>(*value);
  }
  std::optional<std::string> String(const std::string& key) const {
    const YAML::Node node = root_[key];
    if (!node) return std::nullopt;
    if (!node.IsScalar() || node.Scalar().empty())
      throw InputError(Where(node), key, "expected a non-empty text");
    return node.Scalar();
  }
  std::optional<fs::path> Path(const std::string& key) const {
    const auto text = String(key);
    if (!text) return std::nullopt;
    const fs::path p(*text);
    return (p.is_absolute() ? p : file_.parent_path() / p).lexically_normal();
  }

 private:
  fs::path file_;
  YAML::Node root_;
};

std::string RelativeTo(const fs::path& path, const fs::path& base) {
  const fs::path relative = path.lexically_relative(base);
  if (relative.empty() || *relative.begin() == "..") return path.string();
  return relative.string();
}

std::string Quoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

}  // namespace

CameraYaml ReadCameraYaml(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(path, "camera file not found");
  const fs::path file = fs::absolute(path).lexically_normal();
  const YAML::Node root = LoadYamlFile(path);
  if (!root.IsMap()) {
    throw InputError(path, "expected a YAML mapping of camera keys (fx: ..., fy: ..., cx: ..., cy: ...)");
  }
  const YamlMap map(file, root);
  for (const auto& item : root) {
    std::string key;
    try {
      key = item.first.as<std::string>();
    } catch (const YAML::Exception&) {
      throw InputError(map.Where(item.first), "expected text keys");
    }
    if (!KnownKeys().count(key)) {
      throw InputError(map.Where(item.first), key,
                       fmt::format("unknown key; known keys: {}", KnownKeyList()));
    }
  }

  CameraYaml result;
  result.file = file;
  PinholeCamera& c = result.camera;
  c.fx = map.RequiredDouble("fx");
  c.fy = map.RequiredDouble("fy");
  c.cx = map.RequiredDouble("cx");
  c.cy = map.RequiredDouble("cy");
  if (!(c.fx > 0)) throw InputError(map.Where("fx"), "fx", "must be positive");
  if (!(c.fy > 0)) throw InputError(map.Where("fy"), "fy", "must be positive");
  const auto width = map.Int("width");
  const auto height = map.Int("height");
  if (width.has_value() != height.has_value()) {
    throw InputError(map.Where(width ? "width" : "height"), width ? "width" : "height",
                     "give both width and height, or neither");
  }
  if (width) {
    if (*width <= 0) throw InputError(map.Where("width"), "width", "must be positive");
    if (*height <= 0) throw InputError(map.Where("height"), "height", "must be positive");
    c.width = *width;
    c.height = *height;
  }
  c.distortion.k1 = map.Double("k1").value_or(0.0);
  c.distortion.k2 = map.Double("k2").value_or(0.0);
  c.distortion.p1 = map.Double("p1").value_or(0.0);
  c.distortion.p2 = map.Double("p2").value_or(0.0);
  c.distortion.k3 = map.Double("k3").value_or(0.0);

  result.baseline = map.Double("baseline");
  result.right_images = map.Path("right_images");
  if (result.baseline.has_value() != result.right_images.has_value()) {
    const char* given = result.baseline ? "baseline" : "right_images";
    throw InputError(map.Where(given), given, "a stereo pair needs both baseline and right_images");
  }
  if (result.baseline && !(*result.baseline > 0)) {
    throw InputError(map.Where("baseline"), "baseline", "must be positive (metres, right camera along +x)");
  }
  if (result.baseline && !c.distortion.IsZero()) {
    throw InputError(map.Where("baseline"), "baseline", "a stereo pair must be rectified (no distortion)");
  }
  result.fps = map.Double("fps");
  result.times = map.Path("times");
  if (result.fps && result.times) throw InputError(map.Where("fps"), "fps", "give fps or times, not both");
  if (result.fps && !(*result.fps > 0)) throw InputError(map.Where("fps"), "fps", "must be positive");
  result.images = map.Path("images").value_or(file.parent_path());
  result.ground_truth = map.Path("ground_truth");
  result.labels = map.Path("labels");
  result.depth = map.Path("depth");
  result.name = map.String("name");
  return result;
}

void WriteCameraYaml(const fs::path& path, const CameraYaml& y) {
  const fs::path base = fs::absolute(path).parent_path();
  const PinholeCamera& c = y.camera;
  std::string text = "# semslam camera file (docs/formats.md)\n";
  text += fmt::format("fx: {}\nfy: {}\ncx: {}\ncy: {}\n", c.fx, c.fy, c.cx, c.cy);
  if (c.width > 0) text += fmt::format("width: {}\nheight: {}\n", c.width, c.height);
  if (!c.distortion.IsZero()) {
    const Distortion& d = c.distortion;
    text += fmt::format("k1: {}\nk2: {}\np1: {}\np2: {}\nk3: {}\n", d.k1, d.k2, d.p1, d.p2, d.k3);
  }
  if (y.baseline) text += fmt::format("baseline: {}\n", *y.baseline);
  const auto add_path = [&](const char* key, const std::optional<fs::path>& p) {
    if (p) text += fmt::format("{}: {}\n", key, Quoted(RelativeTo(fs::absolute(*p), base)));
  };
  add_path("right_images", y.right_images);
  if (!y.images.empty() && fs::absolute(y.images).lexically_normal() != base.lexically_normal()) {
    add_path("images", y.images);
  }
  if (y.fps) text += fmt::format("fps: {}\n", *y.fps);
  add_path("times", y.times);
  add_path("ground_truth", y.ground_truth);
  add_path("labels", y.labels);
  add_path("depth", y.depth);
  if (y.name) text += fmt::format("name: {}\n", Quoted(*y.name));
  WriteFileAtomically(path, text);
}

std::unique_ptr<ImageSequence> OpenImageFolder(const fs::path& folder_or_yaml) {
  std::error_code ec;
  fs::path yaml = folder_or_yaml;
  if (fs::is_directory(folder_or_yaml, ec)) {
    yaml = folder_or_yaml / "camera.yaml";
    if (!fs::exists(yaml, ec) && fs::exists(folder_or_yaml / "camera.yml", ec))
      yaml = folder_or_yaml / "camera.yml";
  }
  const CameraYaml config = ReadCameraYaml(yaml);
  const SourceLocation at_file{config.file, 0};

  io_internal::SequenceFiles files;
  files.directory = io_internal::NormalizeDirectory(config.images);
  files.name = config.name.value_or(files.directory.filename().string());
  files.camera = config.camera;
  files.calibration = config.file;
  files.left = io_internal::ListFiles(config.images, {".png", ".jpg", ".jpeg"});
  if (files.left.empty()) {
    throw InputError(at_file, "images", fmt::format("no .png/.jpg images in {}", config.images.string()));
  }
  const size_t n = files.left.size();
  if (config.times) {
    const std::vector<double> times = ReadTimes(*config.times);
    if (times.size() < n) {
      throw InputError(*config.times, fmt::format("lists {} timestamps, fewer than the {} images in {}",
                                                  times.size(), n, config.images.string()));
    }
    files.timestamps.assign(times.begin(), times.begin() + static_cast<std::ptrdiff_t>(n));
  } else {
    const double fps = config.fps.value_or(kDefaultFps);
    for (size_t i = 0; i < n; ++i) files.timestamps.push_back(static_cast<double>(i) / fps);
  }
  if (config.right_images) {
    files.right = io_internal::ListFiles(*config.right_images, {".png", ".jpg", ".jpeg"});
    if (files.right.size() != n) {
      throw InputError(
          at_file, "right_images",
          fmt::format("{} holds {} images but {} holds {}: stereo needs one right image per left image",
                      config.right_images->string(), files.right.size(), config.images.string(), n));
    }
    files.baseline = config.baseline;
  }
  if (config.ground_truth) {
    if (DetectTrajectoryFormat(*config.ground_truth) == TrajectoryFormat::kKitti) {
      const std::vector<Rigid3d> poses = ReadKittiPoses(*config.ground_truth);
      if (poses.size() < n) {
        throw InputError(*config.ground_truth,
                         fmt::format("holds {} poses, fewer than the {} images", poses.size(), n));
      }
      Trajectory truth;
      for (size_t i = 0; i < n; ++i) truth.push_back({files.timestamps[i], poses[i]});
      files.ground_truth = std::move(truth);
    } else {
      files.ground_truth = ReadTumTrajectory(*config.ground_truth);
    }
  }
  for (const auto& [key, dir, target] : {std::tuple{"labels", config.labels, &files.labels},
                                         std::tuple{"depth", config.depth, &files.depth}}) {
    if (!dir) continue;
    if (!fs::is_directory(*dir, ec))
      throw InputError(at_file, key, fmt::format("folder {} not found", dir->string()));
    *target = *dir;
  }
  return io_internal::MakeFileSequence(std::move(files));
}

}  // namespace semslam
