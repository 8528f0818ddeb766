#include "system_test_util.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "support/test_support.h"

namespace semslam::system_test {

nlohmann::json ReadJson(const fs::path& path) {
  const std::string text = ReadText(path);
  if (text.empty()) return nlohmann::json();
  return nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::vector<std::string> ErrorLines(const std::string& err) {
  std::vector<std::string> lines;
  for (std::string& line : Lines(err)) {
    const bool log_line =
        line.find("] [info] ") != std::string::npos || line.find("] [warning] ") != std::string::npos;
    if (!log_line) lines.push_back(std::move(line));
  }
  return lines;
}

bool SameBytes(const fs::path& a, const fs::path& b) {
  std::error_code ec_a, ec_b;
  if (fs::file_size(a, ec_a) != fs::file_size(b, ec_b) || ec_a || ec_b) return false;
  return ReadText(a) == ReadText(b);
}

namespace {

std::string BinaryIdentity(const fs::path& binary) {
  std::error_code ec;
  const auto size = fs::file_size(binary, ec);
  const auto time = fs::last_write_time(binary, ec).time_since_epoch().count();
  return binary.string() + "|" + std::to_string(size) + "|" + std::to_string(time);
}

class FileLock {
 public:
  explicit FileLock(const fs::path& path) : fd_(open(path.c_str(), O_RDWR | O_CREAT, 0644)) {
    if (fd_ >= 0) {
      while (flock(fd_, LOCK_EX) != 0 && errno == EINTR) {
      }
    }
  }
  ~FileLock() {
    if (fd_ >= 0) close(fd_);  // releases the lock
  }
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  int fd_;
};

constexpr const char* kErrorFile = "ARTIFACT_ERROR.txt";

}  // namespace

Artifact SharedArtifact(const std::string& name, const std::vector<std::string>& recipe,
                        const std::function<std::string(const fs::path& dir)>& make, const fs::path& binary) {
  std::string key = BinaryIdentity(binary);
  for (const std::string& r : recipe) key += "|" + r;
  std::ostringstream hash;
  hash << std::hex << std::hash<std::string>{}(key);
  const char* env = std::getenv("SEMSLAM_SYSTEM_TEST_CACHE");
  const fs::path root = env != nullptr && *env != '\0' ? fs::path(env) : fs::path(SEMSLAM_SYSTEM_TEST_CACHE);
  fs::create_directories(root);
  const fs::path dir = root / (name + "-" + hash.str());
  const FileLock lock(root / (name + ".lock"));
  Artifact artifact;
  artifact.dir = dir;
  if (!fs::exists(dir)) {
    // Older versions of this artifact (another binary or recipe) go first: they are large.
    for (const auto& entry : fs::directory_iterator(root)) {
      const std::string file = entry.path().filename().string();
      if (entry.is_directory() && file.rfind(name + "-", 0) == 0 && entry.path() != dir) {
        fs::remove_all(entry.path());
      }
    }
    const fs::path partial = root / (name + "-" + hash.str() + ".partial");
    fs::remove_all(partial);
    fs::create_directories(partial);
    std::string error;
    try {
      error = make(partial);
    } catch (const std::exception& e) {
      error = std::string("exception: ") + e.what();
    }
    if (!error.empty()) std::ofstream(partial / kErrorFile) << error;
    fs::rename(partial, dir);
  }
  if (fs::exists(dir / kErrorFile)) {
    artifact.error = name + " could not be made (cached for this binary): " + ReadText(dir / kErrorFile);
  }
  return artifact;
}

Artifact SyntheticTown(const std::string& name, int frames, std::uint64_t seed,
                       const std::vector<std::string>& extra) {
  std::vector<std::string> args = {"synth",  "--frames",           std::to_string(frames),
                                   "--seed", std::to_string(seed), "-q"};
  args.insert(args.end(), extra.begin(), extra.end());
  const fs::path binary = testing::SynthBinary();
  Artifact town = SharedArtifact(
      name, args,
      [&](const fs::path& dir) -> std::string {
        std::vector<std::string> full = args;
        full.insert(full.begin() + 1, {"--out", (dir / "dataset").string()});
        const CommandResult r = testing::RunBinary(binary, full);
        return r.Succeeded() ? "" : r.Describe();
      },
      binary);
  if (town.ok()) town.dir /= "dataset";
  return town;
}

namespace {

// A `semslam run` of `dataset` with extra arguments, into <artifact>/out.
Artifact Run(const std::string& name, const Artifact& dataset, const std::vector<std::string>& extra) {
  if (!dataset.ok()) return {{}, dataset.error};
  std::vector<std::string> args = {"run", "--sequence", SequenceDir(dataset.dir).string(), "-q"};
  args.insert(args.end(), extra.begin(), extra.end());
  Artifact run = SharedArtifact(name, args, [&](const fs::path& dir) -> std::string {
    std::vector<std::string> full = args;
    full.insert(full.end(), {"--out", (dir / "out").string()});
    const CommandResult r = RunSemslam(full);
    std::ofstream(dir / "stdout.txt") << r.out;
    std::ofstream(dir / "stderr.txt") << r.err;
    return r.Succeeded() ? "" : r.Describe();
  });
  if (run.ok()) run.dir /= "out";
  return run;
}

}  // namespace

Artifact SyntheticDataset() { return SyntheticTown("city200", kSyntheticFrames, 1); }

Artifact ComposedRun(const std::string& name, const std::vector<std::string>& compose,
                     const std::vector<std::string>& run) {
  std::vector<std::string> recipe = compose;
  recipe.insert(recipe.end(), run.begin(), run.end());
  return SharedArtifact(name, recipe, [&](const fs::path& dir) -> std::string {
    std::vector<std::string> c = compose;
    c.insert(c.end(), {"--out", (dir / "sequence").string()});
    CommandResult r = RunSemslam(c);
    if (!r.Succeeded()) return r.Describe();
    std::vector<std::string> full = run;
    full.insert(full.end(), {"--sequence", (dir / "sequence").string(), "--out", (dir / "out").string()});
    r = RunSemslam(full);
    return r.Succeeded() ? "" : r.Describe();
  });
}

std::vector<std::string> LookAlikeBlackOutRunArgs() {
  return {"run", "--mode", "mono", "--frames", "640:", "--pacing", "synchronous", "--segmenter", "none"};
}

Artifact LookAlikeBlackOutRun() {
  constexpr int kFrames = 800;
  const Artifact town = SyntheticTown("town2027_800", kFrames, 2027);
  if (!town.ok()) return town;
  const std::vector<std::string> compose = {"compose",
                                            "--sequence",
                                            SequenceDir(town.dir).string(),
                                            "--frames",
                                            "0-" + std::to_string(kFrames - 1),
                                            "--black",
                                            "750:770",
                                            "-q"};
  std::vector<std::string> run = LookAlikeBlackOutRunArgs();
  run.push_back("-q");
  return ComposedRun("town2027_800_black750", compose, run);
}

Artifact TinyDataset() { return SyntheticTown("city6", 6, 1); }

Artifact MonoRun() {
  const Artifact city = SyntheticDataset();
  if (!city.ok()) return city;
  const fs::path data = city.dir;
  return Run("mono_run", city,
             {"--mode", "mono", "--pacing", "synchronous", "--segmenter", "truth-noisy:0.25", "--gps",
              (data / "oxts").string(), "--landmarks", (data / "landmarks.csv").string()});
}

Artifact SecondDriveDataset() {
  return SyntheticTown("city200_traffic2", kSyntheticFrames, 1, {"--traffic-seed", "2"});
}

Artifact SecondDriveMonoRun() {
  const Artifact city = SecondDriveDataset();
  if (!city.ok()) return city;
  const fs::path data = city.dir;
  return Run("mono_run_traffic2", city,
             {"--mode", "mono", "--pacing", "synchronous", "--segmenter", "truth-noisy:0.25", "--gps",
              (data / "oxts").string(), "--landmarks", (data / "landmarks.csv").string()});
}

Artifact StereoRun() {
  return Run("stereo_run", SyntheticDataset(), {"--mode", "stereo", "--pacing", "synchronous"});
}

Artifact SecondDriveStereoRun() {
  return Run("stereo_run_traffic2", SecondDriveDataset(), {"--mode", "stereo", "--pacing", "synchronous"});
}

Artifact TinyStereoRun() {
  return Run("tiny_stereo_run", TinyDataset(), {"--mode", "stereo", "--pacing", "synchronous"});
}

std::vector<double> Timestamps(const Trajectory& trajectory) {
  std::vector<double> stamps;
  for (const StampedPose& p : trajectory) stamps.push_back(p.timestamp);
  return stamps;
}

std::vector<int> FrameIndices(const std::vector<double>& timestamps, const std::vector<double>& times) {
  std::vector<int> indices;
  for (const double t : timestamps) {
    const auto it = std::lower_bound(times.begin(), times.end(), t - 1e-3);
    indices.push_back(it != times.end() && std::abs(*it - t) <= 1e-3 ? static_cast<int>(it - times.begin())
                                                                     : -1);
  }
  return indices;
}

}  // namespace semslam::system_test
