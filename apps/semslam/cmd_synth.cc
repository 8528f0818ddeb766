#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <optional>
#include <string>

#include "cli_support.h"
#include "commands.h"
#include "semslam/core/error.h"
#include "semslam/sim/dataset_writer.h"
#include "semslam/sim/synthetic_city.h"

namespace semslam::cli {
namespace {

struct SynthArgs {
  std::string out;
  std::string preset = "default";
  std::optional<long long> frames;
  std::optional<long long> seed;
  std::optional<long long> traffic_seed;
  std::optional<long long> route_seed;
  std::optional<double> gps_noise;
  std::optional<long long> gps_every;
  std::optional<double> gps_dropout;
  std::optional<double> gps_outliers;
  std::optional<double> lat, lon, alt;
  std::optional<double> start_epoch;
  bool reverse = false;
  bool overwrite = false;
  bool quiet = false;
};

std::uint64_t Seed(long long value, const char* name) {
  Require(value > 0, std::string(name) + " must be a positive integer");
  return static_cast<std::uint64_t>(value);
}

void Synth(const SynthArgs& a) {
  sim::SynthOptions o = sim::PresetOptions(a.preset);
  if (a.frames) {
    Require(*a.frames >= 1 && *a.frames <= 1000000, "--frames must be in [1, 1000000]");
    o.route.frames = static_cast<int>(*a.frames);
  }
  if (a.seed) o.city.seed = Seed(*a.seed, "--seed");
  if (a.traffic_seed) o.city.traffic_seed = Seed(*a.traffic_seed, "--traffic-seed");
  if (a.route_seed) o.route.route_seed = Seed(*a.route_seed, "--route-seed");
  o.route.reverse = a.reverse;
  if (a.gps_noise) o.gps.noise = *a.gps_noise;
  if (a.gps_every) {
    Require(*a.gps_every >= 1 && *a.gps_every <= 1000000, "--gps-every must be a positive number of frames");
    o.gps.every = static_cast<int>(*a.gps_every);
  }
  if (a.gps_dropout) o.gps.dropout = *a.gps_dropout;
  if (a.gps_outliers) o.gps.outliers = *a.gps_outliers;
  if (a.lat) o.gps.origin.latitude_deg = *a.lat;
  if (a.lon) o.gps.origin.longitude_deg = *a.lon;
  if (a.alt) o.gps.origin.altitude_m = *a.alt;
  if (a.start_epoch) o.gps.start_epoch = *a.start_epoch;
  o.Check();
  const sim::SyntheticCity city(o);
  spdlog::info(
      "synth: town of seed {} ({} blocks){}, {} frames, {:.0f} m, {} turns, {} revisits, {} landmarks -> {}",
      o.city.seed, o.city.blocks_x * o.city.blocks_y,
      a.route_seed ? ", route seed " + std::to_string(*a.route_seed) : std::string(), city.num_frames(),
      city.route().length, city.route().turns.size(), city.Revisits().size(), city.Landmarks().size(), a.out);
  sim::DatasetOptions d;
  d.progress = !a.quiet && !Quiet();
  d.overwrite = a.overwrite;
  sim::WriteDataset(city, a.out, d);
}

}  // namespace

void AddSynthCommand(CLI::App& app) {
  auto* cmd =
      app.add_subcommand("synth", "Render the synthetic city as a KITTI-layout dataset with ground truth");
  auto args = std::make_shared<SynthArgs>();
  cmd->add_option("--out", args->out, "Output folder (sequences/00, poses, oxts, landmarks.csv, scene.json)")
      ->required();
  cmd->add_option("--frames", args->frames, "Number of frames at 10 Hz (default 1200)");
  cmd->add_option("--seed", args->seed, "Town seed (default 1)");
  cmd->add_option("--preset", args->preset, "Option set: default, small, dense, static")
      ->capture_default_str();
  cmd->add_option("--gps-noise", args->gps_noise, "GPS position noise, metres (default 1.0)");
  cmd->add_option("--gps-every", args->gps_every, "A GPS fix every N frames (default 1)");
  cmd->add_option("--gps-dropout", args->gps_dropout,
                  "Probability that a fix is missing, never the first (default 0)");
  cmd->add_option("--gps-outliers", args->gps_outliers,
                  "Fraction of fixes replaced by 50 m outliers (default 0)");
  cmd->add_option("--traffic-seed", args->traffic_seed,
                  "Seed of the parked cars, persons and bicycles (a second drive through the same town)");
  cmd->add_option(
      "--route-seed", args->route_seed,
      "Another drive through the same town (same streets, landmarks and origin): drives of any two "
      "route seeds share streets both ways; without it, the town's first route");
  cmd->add_flag("--reverse", args->reverse, "Drive the same streets in the opposite direction");
  cmd->add_flag("--overwrite", args->overwrite, "Replace an earlier synthetic dataset in the output folder");
  cmd->add_option("--origin-lat", args->lat, "WGS84 latitude of the town origin (default 49.0)");
  cmd->add_option("--origin-lon", args->lon, "WGS84 longitude of the town origin (default 8.4)");
  cmd->add_option("--origin-alt", args->alt, "Altitude of the town origin, metres (default 115)");
  cmd->add_option("--start-epoch", args->start_epoch,
                  "Unix time of frame 0 for the oxts timestamps (default 1600000000)");
  cmd->add_flag("-q,--quiet", args->quiet, "Only errors on stderr (no log messages, no progress lines)");
  cmd->callback([args] { Synth(*args); });
}

}  // namespace semslam::cli
