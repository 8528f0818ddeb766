#pragma once
// Helpers of the end-to-end tests: reading what the `semslam` binary wrote (it runs through RunSemslam of
// support/test_support.h), and the datasets and runs that several tests share.
//
// CTest runs every test in a process of its own (and two at a time with -j2), so what several tests need is
// made once into a cache directory under the build tree, keyed by the semslam binary (size and modification
// time) and the exact command, under a file lock: the first test to need it makes it, the others wait and
// reuse it, and a rebuilt binary makes it again. SEMSLAM_SYSTEM_TEST_CACHE overrides the cache directory.

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "semslam/geometry/trajectory.h"
#include "support/test_support.h"

namespace semslam::system_test {

namespace fs = std::filesystem;

// Running the binary and reading files come from the shared test support.
using testing::CommandResult;
using testing::ReadText;
using testing::RunSemslam;

nlohmann::json ReadJson(const fs::path& path);
// The lines of a text (a last line without '\n' counts; an empty text has none).
std::vector<std::string> Lines(const std::string& text);
// The lines of a run's stderr that report an error: all but its info and warning log lines.
std::vector<std::string> ErrorLines(const std::string& err);
bool SameBytes(const fs::path& a, const fs::path& b);

// A shared, cached result: `dir` when it was made, else `error` says why not.
struct Artifact {
  fs::path dir;
  std::string error;
  bool ok() const { return error.empty(); }
};

// Makes (once per `binary` and recipe) a directory with `make(dir)`, which returns "" on success or what went
// wrong (a failure is cached too, so that tests sharing a broken run fail fast with the same message).
Artifact SharedArtifact(const std::string& name, const std::vector<std::string>& recipe,
                        const std::function<std::string(const fs::path& dir)>& make,
                        const fs::path& binary = testing::SemslamBinary());

// `semslam synth --frames F --seed S` rendered by testing::SynthBinary() (once per that binary), as the
// artifact `name`; its dir is the dataset.
// `extra`: more synth arguments (e.g. --route-seed).
Artifact SyntheticTown(const std::string& name, int frames, std::uint64_t seed,
                       const std::vector<std::string>& extra = {});

// `semslam synth --out DIR --frames 200 --seed 1`: the synthetic city, 200 frames (~195 m, one left turn,
// eight landmarks, GPS every frame with 1 m noise).
constexpr int kSyntheticFrames = 200;
Artifact SyntheticDataset();
// A 6-frame synthetic dataset (fixtures for bad inputs).
Artifact TinyDataset();
// `semslam run --sequence D --mode mono --pacing synchronous --segmenter truth-noisy:0.25 --gps D/oxts
// --landmarks D/landmarks.csv` over the 200-frame city: the one monocular run of the suite (SLAM, semantics,
// GPS and landmarks; semantics and geography come after tracking and do not change it).
Artifact MonoRun();
// The same streets driven again (`synth --traffic-seed 2`, 200 frames: other parked cars, GPS and sensor
// noise), and the same run as MonoRun over it.
Artifact SecondDriveDataset();
Artifact SecondDriveMonoRun();
// `semslam run --sequence D --mode stereo --pacing synchronous` over the 200-frame city.
Artifact StereoRun();
// The second drive, stereo at synchronous pacing, no GPS.
Artifact SecondDriveStereoRun();

// `semslam run --mode stereo --pacing synchronous` over the 6-frame dataset (a small map.semslam).
Artifact TinyStereoRun();

// `compose` (a sequence cut, blacked out or reversed) into DIR/sequence, then `run` on it into DIR/out, made
// once as the artifact `name`. `run` names no --sequence or --out.
Artifact ComposedRun(const std::string& name, const std::vector<std::string>& compose,
                     const std::vector<std::string>& run);

// Seed 2027's town, 800 frames, composed with frames 750-769 black; run monocular at synchronous pacing, no
// segmenter, from frame 640: tracking is lost in the black-out and a new map starts at frame 770.
Artifact LookAlikeBlackOutRun();
// That run's arguments, without --sequence, --out and -q.
std::vector<std::string> LookAlikeBlackOutRunArgs();

// The sequence folder of a synthetic dataset.
inline fs::path SequenceDir(const fs::path& dataset) { return dataset / "sequences" / "00"; }

// The timestamps of a trajectory, in order.
std::vector<double> Timestamps(const Trajectory& trajectory);
// Frame index of each timestamp of a trajectory file (TUM), through the sequence's times.txt (within 1 ms);
// -1 where none matches.
std::vector<int> FrameIndices(const std::vector<double>& timestamps, const std::vector<double>& times);

}  // namespace semslam::system_test

// Declares `var` as the artifact's directory, failing the test when it could not be made.
#define SEMSLAM_ASSERT_ARTIFACT(var, expression)                        \
  const ::semslam::system_test::Artifact var##_artifact = (expression); \
  ASSERT_TRUE(var##_artifact.ok()) << var##_artifact.error;             \
  const std::filesystem::path var = var##_artifact.dir
