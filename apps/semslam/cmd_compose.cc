// semslam compose: a sequence made of another one's frames (played back and forth, cut, blacked out), to
// test losing tracking, new maps and merges on real drives.

#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "cli_support.h"
#include "commands.h"
#include "semslam/io/sequence.h"
#include "semslam/io/sequence_composer.h"
#include "semslam/system/sequence_runner.h"

namespace semslam::cli {
namespace {

struct ComposeArgs {
  std::string sequence;
  std::string out;
  std::string frames;
  std::string black;
  bool stereo = false;
  bool quiet = false;
};

void Compose(const ComposeArgs& a) {
  const std::unique_ptr<ImageSequence> source = OpenSequence(a.sequence);
  size_t black_first = 0, black_end = 0;
  if (!a.black.empty()) ParseFrameRange(a.black, &black_first, &black_end);
  WriteComposedSequence(*source,
                        ComposeFrames(ParseFrameList(a.frames, source->size()), black_first, black_end),
                        a.out, a.stereo, /*show_progress=*/!a.quiet && !Quiet());
}

}  // namespace

void AddComposeCommand(CLI::App& app) {
  auto args = std::make_shared<ComposeArgs>();
  auto* cmd = app.add_subcommand(
      "compose",
      "Make a sequence of another one's frames (back and forth, cut, blacked out) as an image folder");
  cmd->add_option("--sequence", args->sequence, "Source sequence (any that `run` reads)")->required();
  cmd->add_option(
         "--out", args->out,
         "Output folder (new or empty): images, times.txt, gt.txt, labels and depth (when the source "
         "has them), camera.yaml")
      ->required();
  cmd->add_option("--frames", args->frames,
                  "Source frames in order: ranges A-B (A > B runs backwards) and frames, comma-separated, "
                  "e.g. 0-159,158-0,1-159; leave frames out to cut")
      ->required();
  cmd->add_option("--black", args->black, "Composed frames A:B (A..B-1) as black images");
  cmd->add_flag("--stereo", args->stereo, "Write the right images too (when the source has them)");
  cmd->add_flag("-q,--quiet", args->quiet, "Only errors on stderr (no log messages, no progress lines)");
  cmd->callback([args] { Compose(*args); });
}

}  // namespace semslam::cli
