#pragma once
// A model card: how to feed a segmentation network and read its output, as a small YAML file.
// clang-format off
//
//   name: enet-cityscapes
//   file: ${SEMSLAM_SHARED_DATA:-../../shared/data}/enet_cityscapes_torch/enet-model.net  # relative to the card
//   format: torch          # torch | onnx | pth | auto (by extension: .net/.t7 torch, .onnx onnx, .pth/.pt pth)
//   architecture: sinet    # pth only: the network semslam builds for the state dict (torch_networks.h)
//   input:
//     width: 1024          # network input size; with fixed: true images are stretched to exactly this
//     height: 512
//     fixed: true          # false: any size; width/height (optional) is then the size used; width alone: the
//                          # image is scaled to this width, aspect ratio kept (both sides rounded to size_divisor)
//     resize: stretch      # fixed size: stretch the image to it, or tile: keep the aspect ratio, scale the image
//                          # to the input height and run overlapping windows across it (averaged)
//     size_divisor: 32     # not fixed and no width/height: the image size rounded to a multiple of this
//     channel_order: rgb   # rgb | bgr (grey images are fed as three equal channels)
//     scale: 0.00392156862745098
//     mean: [0, 0, 0]      # x = (pixel * scale - mean) / std, per channel in channel_order
//     std: [1, 1, 1]
//   output:
//     name: ""             # output blob name; empty = the network's last output
//     layout: nchw         # nchw | nhwc (scores per class) | labels (class indices, N x H x W)
//     scores: logits       # logits (softmax applied) | probabilities | log_probabilities
//     classes: [none, road, sidewalk, ...]
//                          # output channel -> class name or trainId; none/unlabeled/-1/255: a "no class"
//                          # channel (its probability is spread evenly); drop: the channel is left out before
//                          # the softmax; "cityscapes" = the 19 trainIds in order (the default)
// clang-format on
//
// `${VAR}` and `${VAR:-default}` in `file` are expanded from the environment; a relative result is relative
// to the card's folder.

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "semslam/semantics/segmentation.h"

namespace semslam {

// In a card's class list: an output channel left out of the class distribution altogether.
inline constexpr std::uint8_t kDropChannel = 254;

struct ModelCard {
  enum class Format { kAuto, kTorch, kOnnx, kPth };
  enum class Layout { kNchw, kNhwc, kLabels };

  std::string name;
  std::filesystem::path file;
  Format format = Format::kAuto;
  std::string architecture;  // kPth: "espnetv2" or "sinet"
  int input_width = 0;  // 0: the image's (rounded to size_divisor); alone (height 0): keep the aspect ratio
  int input_height = 0;
  bool fixed_size = false;
  enum class Resize { kStretch, kTile } resize = Resize::kStretch;
  int size_divisor = 32;
  bool rgb = true;
  double scale = 1.0;
  std::array<double, 3> mean{0.0, 0.0, 0.0};
  std::array<double, 3> stddev{1.0, 1.0, 1.0};  // "std" in the card
  std::string output_name;
  Layout layout = Layout::kNchw;
  ScoreKind scores = ScoreKind::kLogits;
  // Output channel (or label index) -> trainId, kNoLabel for "no class", kDropChannel for a channel left out.
  std::vector<std::uint8_t> channel_to_train_id;

  // Throws InvalidArgument naming the bad field.
  void Check() const;
  // The format, resolved from the file's extension when kAuto.
  Format ResolvedFormat() const;
};

// Reads and checks a model card. Throws InputError naming the file, line and field.
ModelCard ReadModelCard(const std::filesystem::path& path);
// Parses a card from YAML text; relative files are resolved against `base_dir`. `source` names it in errors.
ModelCard ParseModelCard(const std::string& yaml, const std::filesystem::path& base_dir,
                         const std::filesystem::path& source);

// The ENet Cityscapes model of e-lab (Torch7): RGB, scale 1/255, no mean/std, fixed 1024x512 input (other
// sizes give nearly all 'unlabeled' with OpenCV 4.6), 20 logit channels: 0 = unlabeled, trainId = channel
// - 1.
ModelCard EnetCityscapesCard(const std::filesystem::path& weights);
// ESPNetv2 s=2.0 and SINet with their published Cityscapes state dicts (.pth): RGB, ImageNet mean and std,
// logits. ESPNetv2's 20th channel (background) is dropped. `width`: the network input width (images are
// scaled to it, aspect ratio kept); 0 for the default (ESPNetv2 1024, SINet 1280).
ModelCard EspNetV2CityscapesCard(const std::filesystem::path& weights, int width = 0);
ModelCard SiNetCityscapesCard(const std::filesystem::path& weights, int width = 0);

// Expands ${VAR} and ${VAR:-default} from the environment. Throws InvalidArgument for an unset variable
// without a default or an unterminated reference.
std::string ExpandEnvironment(const std::string& text);

}  // namespace semslam
