#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "commands.h"
#include "semslam/core/error.h"
#include "semslam/core/interrupt.h"
#include "semslam/core/progress.h"
#include "semslam/core/text_reader.h"
#include "semslam/core/timing.h"
#include "semslam/place/retrieval_evaluation.h"
#include "semslam/place/vocabulary.h"
#include "semslam/place/vocabulary_builder.h"

namespace semslam::cli {
namespace {

void PrintSummary(const Vocabulary& vocabulary, const std::filesystem::path& path) {
  std::error_code ec;
  const auto bytes = std::filesystem::file_size(path, ec);
  std::fprintf(
      stderr, "vocabulary %s: k = %d, L = %d, %zu words, %zu nodes, %s descriptors, %.2f MB\n",
      path.string().c_str(), vocabulary.branching(), vocabulary.depth(), vocabulary.size(),
      vocabulary.num_nodes(),
      vocabulary.descriptor_pattern() == OrbDescriptorPattern::kOpenCv ? "OpenCV-pattern ORB" : "semslam ORB",
      ec ? 0.0 : static_cast<double>(bytes) / 1e6);
}

struct TrainArgs {
  std::vector<std::string> image_dirs;
  size_t procedural = 0;
  std::string out;
  int k = 10;
  int levels = 4;
  size_t max_images = 0;
  int features = 1000;
  int iterations = 10;
  std::uint64_t seed = 1;
  bool opencv_pattern = false;
};

// Ctrl-C: the long steps (feature extraction, training) end at the next progress report; nothing is written.
void StopIfInterrupted(const char* command) {
  if (InterruptRequested()) {
    throw Interrupted(InterruptSignal(),
                      fmt::format("{}: interrupted by {}; nothing written", command, InterruptName()));
  }
}

void Train(const TrainArgs& args) {
  Stopwatch watch;
  if (args.image_dirs.empty() == (args.procedural == 0)) {
    throw InvalidArgument("vocab train: give either --images or --procedural");
  }
  OrbOptions orb;
  orb.num_features = args.features;
  orb.pattern = args.opencv_pattern ? OrbDescriptorPattern::kOpenCv : OrbDescriptorPattern::kSemslam;
  orb.Check();
  std::vector<std::vector<Descriptor>> descriptors;
  if (args.procedural > 0) {
    std::fprintf(stderr, "vocab train: %zu procedural images, %d features each\n", args.procedural, args.features);
    ProgressReporter progress("extracting features", args.procedural);
    descriptors = ExtractProceduralDescriptors(args.procedural, cv::Size(1241, 376), orb, args.seed,
                                               [&](size_t done, size_t) {
                                                 StopIfInterrupted("vocab train");
                                                 progress.Update(done);
                                               });
    progress.Finish();
  } else {
    std::vector<std::filesystem::path> folders(args.image_dirs.begin(), args.image_dirs.end());
    const auto images = ListTrainingImages(folders, args.max_images);
    std::fprintf(stderr, "vocab train: %zu images, %d features each\n", images.size(), args.features);
    ProgressReporter progress("extracting features", images.size());
    descriptors = ExtractTrainingDescriptors(images, orb, [&](size_t done, size_t) {
      StopIfInterrupted("vocab train");
      progress.Update(done);
    });
    progress.Finish();
  }
  VocabularyTrainingOptions options;
  options.branching = args.k;
  options.depth = args.levels;
  options.max_iterations = args.iterations;
  options.seed = args.seed;
  options.pattern = orb.pattern;
  const Vocabulary vocabulary = Vocabulary::Train(descriptors, options, [](const std::string& line) {
    StopIfInterrupted("vocab train");
    std::fprintf(stderr, "%s\n", line.c_str());
  });
  StopIfInterrupted("vocab train");
  vocabulary.Save(args.out);
  PrintSummary(vocabulary, args.out);
  std::fprintf(stderr, "vocab train: done in %.1f s\n", watch.ElapsedSeconds());
}

struct EvalArgs {
  std::string vocabulary;
  std::string sequence;
  std::string poses;
  int features = 2000;
  size_t max_frames = 0;
  RetrievalOptions retrieval;
};

// KITTI poses: 12 numbers per line, the 3x4 camera-to-world matrix row by row.
void ReadKittiCentres(const std::filesystem::path& path, std::vector<Eigen::Vector3d>& centres,
                      std::vector<Eigen::Vector3d>& directions) {
  TextReader reader(path);
  while (auto line = reader.NextLine()) {
    const auto tokens = SplitTokens(*line);
    if (tokens.empty()) continue;
    const auto values = ParseVector<12>(tokens, reader.Where(), "pose");
    centres.emplace_back(values[3], values[7], values[11]);
    directions.emplace_back(values[2], values[6], values[10]);
  }
}

void Eval(const EvalArgs& args) {
  const Vocabulary vocabulary = Vocabulary::Load(args.vocabulary);
  const std::filesystem::path sequence(args.sequence);
  std::filesystem::path poses = args.poses;
  if (poses.empty()) {
    // KITTI layout: <root>/sequences/<name>/ with <root>/poses/<name>.txt.
    poses = sequence.parent_path().parent_path() / "poses" / (sequence.filename().string() + ".txt");
    if (sequence.filename().empty()) {
      poses = sequence.parent_path().parent_path().parent_path() / "poses" /
              (sequence.parent_path().filename().string() + ".txt");
    }
  }
  std::vector<Eigen::Vector3d> centres, directions;
  ReadKittiCentres(poses, centres, directions);
  auto images = ListTrainingImages({sequence}, 0);
  if (images.size() > centres.size()) images.resize(centres.size());
  if (args.max_frames > 0 && images.size() > args.max_frames) images.resize(args.max_frames);
  centres.resize(images.size());
  directions.resize(images.size());
  OrbOptions orb;
  orb.num_features = args.features;
  orb.pattern = vocabulary.descriptor_pattern();
  ProgressReporter progress("extracting features", images.size());
  const auto descriptors = ExtractTrainingDescriptors(images, orb, [&](size_t done, size_t) {
    StopIfInterrupted("vocab eval");
    progress.Update(done);
  });
  progress.Finish();
  const RetrievalResult r = EvaluateRetrieval(vocabulary, descriptors, centres, directions, args.retrieval);
  std::printf(
      "{\"frames\": %zu, \"queries\": %d, \"revisits\": %d, \"top1\": %d, \"top5\": %d, \"top1_rate\": %.4f, "
      "\"top5_rate\": %.4f, \"median_true_score\": %.4f, \"median_other_score\": %.4f, \"false_top1\": %d}\n",
      images.size(), r.queries, r.revisits, r.top1, r.top5, r.Top1Rate(), r.Top5Rate(), r.median_true_score,
      r.median_other_score, r.false_top1);
}

}  // namespace

void AddVocabCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("vocab", "Train, convert or inspect a bag-of-words vocabulary");
  cmd->require_subcommand(1);

  auto args = std::make_shared<TrainArgs>();
  auto* train = cmd->add_subcommand("train", "Train a vocabulary on the ORB features of image folders");
  train
      ->add_option("--images", args->image_dirs,
                   "Image folders (or KITTI-layout datasets: DIR/image_0, DIR/sequences/*/image_0)")
      ->expected(1, -1);
  train->add_option("--procedural", args->procedural,
                    "Instead of --images: this many procedurally drawn 1241x376 images (no data needed)");
  train->add_option("--out", args->out, "Vocabulary file to write")->required();
  train->add_option("--k", args->k, "Branching factor")->capture_default_str()->check(CLI::Range(2, 256));
  train->add_option("--levels", args->levels, "Depth of the tree (levels below the root)")
      ->capture_default_str()
      ->check(CLI::Range(1, 16));
  train->add_option("--max-images", args->max_images, "Use at most this many images, evenly spread (0: all)")
      ->capture_default_str();
  train->add_option("--features", args->features, "ORB features per image")
      ->capture_default_str()
      ->check(CLI::Range(10, 100000));
  train->add_option("--iterations", args->iterations, "k-majority iterations per node")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  train->add_option("--seed", args->seed, "Seed of the k-means++ seeding")->capture_default_str();
  train->add_flag(
      "--opencv-pattern", args->opencv_pattern,
      "Describe features with OpenCV's ORB pattern (as DBoW2 vocabularies such as ORBvoc.txt do)");
  train->callback([args] { Train(*args); });

  auto dbow2 = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto* convert =
      cmd->add_subcommand("convert", "Convert a DBoW2 text vocabulary (ORBvoc.txt) to semslam's format");
  convert->add_option("--dbow2", *dbow2, "DBoW2 text vocabulary")->required();
  convert->add_option("--out", *out, "Vocabulary file to write")->required();
  convert->callback([dbow2, out] {
    Stopwatch watch;
    std::fprintf(stderr, "vocab convert: reading %s\n", dbow2->c_str());
    const Vocabulary vocabulary = Vocabulary::LoadDbow2Text(*dbow2);
    std::fprintf(stderr, "vocab convert: read %zu nodes in %.1f s, writing %s\n", vocabulary.num_nodes(),
                 watch.ElapsedSeconds(), out->c_str());
    vocabulary.Save(*out);
    PrintSummary(vocabulary, *out);
  });

  auto file = std::make_shared<std::string>();
  auto* info = cmd->add_subcommand("info", "Print a vocabulary's parameters");
  info->add_option("file", *file, "Vocabulary file (semslam or DBoW2 text)")->required();
  info->callback([file] { PrintSummary(Vocabulary::Load(*file), *file); });

  auto eval = std::make_shared<EvalArgs>();
  auto* evaluate = cmd->add_subcommand("eval",
                                       "Place-recognition quality on a sequence with poses: does the best "
                                       "database frame show the same place?");
  evaluate->add_option("--vocabulary", eval->vocabulary, "Vocabulary file")->required();
  evaluate->add_option("--sequence", eval->sequence, "KITTI-layout sequence folder (with image_0/)")
      ->required();
  evaluate->add_option("--poses", eval->poses, "KITTI poses file (default: <root>/poses/<name>.txt)");
  evaluate->add_option("--features", eval->features, "ORB features per frame")->capture_default_str();
  evaluate->add_option("--max-frames", eval->max_frames, "Use only the first N frames (0: all)")
      ->capture_default_str();
  evaluate->add_option("--every", eval->retrieval.database_every, "Every n-th frame enters the database")
      ->capture_default_str();
  evaluate
      ->add_option("--exclude-recent", eval->retrieval.exclude_recent,
                   "Database frames this recent are not candidates")
      ->capture_default_str();
  evaluate->add_option("--distance", eval->retrieval.same_place_distance, "Same place: centres within (m)")
      ->capture_default_str();
  evaluate->add_option("--angle", eval->retrieval.same_place_angle_deg, "Same place: directions within (deg)")
      ->capture_default_str();
  evaluate->callback([eval] { Eval(*eval); });
}

}  // namespace semslam::cli
