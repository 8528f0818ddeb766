#include "semslam/semantics/segmenter.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>
#include <vector>

#include "semslam/core/error.h"
#include "semslam/semantics/dnn_segmenter.h"
#include "semslam/semantics/label_image_segmenter.h"
#include "semslam/semantics/model_card.h"

namespace semslam {
namespace {

bool IsSettingKey(std::string_view key) {
  static const char* const kKeys[] = {"alpha",     "ids",     "seed",   "blobs",
                                      "blob_size", "threads", "resize", "width"};
  for (const char* k : kKeys) {
    if (key == k) return true;
  }
  return false;
}

struct ParsedSpec {
  std::string kind;
  std::string argument;
  std::map<std::string, std::string> settings;
};

ParsedSpec ParseSpec(std::string_view spec) {
  ParsedSpec parsed;
  std::string text(spec);
  // Trailing ",key=value" settings (a path may itself contain commas: only known keys are split off).
  for (;;) {
    const size_t comma = text.rfind(',');
    if (comma == std::string::npos) break;
    const std::string tail = text.substr(comma + 1);
    const size_t eq = tail.find('=');
    if (eq == std::string::npos || !IsSettingKey(tail.substr(0, eq))) break;
    parsed.settings[tail.substr(0, eq)] = tail.substr(eq + 1);
    text.resize(comma);
  }
  const size_t colon = text.find(':');
  parsed.kind = text.substr(0, colon);
  for (char& c : parsed.kind) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (colon != std::string::npos) parsed.argument = text.substr(colon + 1);
  return parsed;
}

double ParseNumber(const std::string& text, const std::string& what) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  Require(!text.empty() && end != text.c_str() && *end == '\0' && std::isfinite(v),
          "segmenter spec: " + what + " '" + text + "' is not a number");
  return v;
}

}  // namespace

std::filesystem::path DefaultSegmentationWeightsDir() {
  const char* shared = std::getenv("SEMSLAM_SHARED_DATA");
  if (shared != nullptr && *shared != '\0') return std::filesystem::path(shared) / "segmentation_weights";
  const std::filesystem::path beside_cwd = std::filesystem::path("../shared/data/segmentation_weights");
  if (std::filesystem::is_directory(beside_cwd)) return beside_cwd;
  // Run from elsewhere, a binary of the build tree (CHECKOUT/build/PRESET/bin) still finds the data beside
  // its checkout.
  std::error_code error;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", error);
  if (!error) {
    const std::filesystem::path beside_checkout =
        (exe.parent_path() / "../../../../shared/data/segmentation_weights").lexically_normal();
    if (std::filesystem::is_directory(beside_checkout)) return beside_checkout;
  }
  return beside_cwd;
}

std::unique_ptr<Segmenter> MakeSegmenter(std::string_view spec, const SegmenterContext& context) {
  const ParsedSpec p = ParseSpec(spec);
  const auto setting = [&](const std::string& key) -> const std::string* {
    const auto it = p.settings.find(key);
    return it == p.settings.end() ? nullptr : &it->second;
  };
  const auto allow = [&](std::initializer_list<std::string_view> keys) {
    for (const auto& [key, value] : p.settings) {
      bool ok = false;
      for (std::string_view k : keys) ok = ok || key == k;
      Require(ok, "segmenter spec '" + std::string(spec) + "': setting '" + key + "' does not apply to " +
                      p.kind);
    }
  };
  const auto need_argument = [&](const char* what) {
    Require(!p.argument.empty(), "segmenter spec '" + std::string(spec) + "': " + p.kind + " needs " + what);
  };

  if (p.kind == "none" || p.kind.empty()) {
    Require(p.argument.empty() && p.settings.empty(), "segmenter spec 'none' takes no argument");
    return nullptr;
  }
  if (p.kind == "enet" || p.kind == "onnx" || p.kind == "card" || p.kind == "dnn") {
    allow({"threads", "resize"});
    need_argument(p.kind == "enet" ? "the model file (enet:FILE)" : "a model card (onnx:CARD.yaml)");
    DnnSegmenter::Options options;
    if (const auto* t = setting("threads")) options.threads = static_cast<int>(ParseNumber(*t, "threads"));
    const std::filesystem::path argument(p.argument);
    const std::string ext = argument.extension().string();
    ModelCard card = (p.kind == "enet" && ext != ".yaml" && ext != ".yml") ? EnetCityscapesCard(argument)
                                                                           : ReadModelCard(argument);
    if (const auto* r = setting("resize")) {
      Require(*r == "stretch" || *r == "tile", "segmenter spec: resize must be 'stretch' or 'tile'");
      card.resize = *r == "tile" ? ModelCard::Resize::kTile : ModelCard::Resize::kStretch;
    }
    return std::make_unique<DnnSegmenter>(std::move(card), options);
  }
  if (p.kind == "espnetv2" || p.kind == "sinet") {
    allow({"threads", "width"});
    need_argument(p.kind == "sinet" ? "the state dict (sinet:FILE.pth)"
                                    : "the state dict (espnetv2:FILE.pth)");
    DnnSegmenter::Options options;
    if (const auto* t = setting("threads")) options.threads = static_cast<int>(ParseNumber(*t, "threads"));
    int width = 0;
    if (const auto* w = setting("width")) {
      const double v = ParseNumber(*w, "width");
      Require(v >= 64 && v <= 8192 && v == std::floor(v),
              "segmenter spec: width must be an integer in 64..8192");
      width = static_cast<int>(v);
    }
    ModelCard card = p.kind == "sinet" ? SiNetCityscapesCard(p.argument, width)
                                       : EspNetV2CityscapesCard(p.argument, width);
    return std::make_unique<DnnSegmenter>(std::move(card), options);
  }
  if (p.kind == "auto") {
    allow({"threads", "width"});
    const std::filesystem::path dir =
        p.argument.empty() ? DefaultSegmentationWeightsDir() : std::filesystem::path(p.argument);
    std::string resolved = context.colour_images
                               ? "sinet:" + (dir / "sinet_cityscapes.pth").string()
                               : "espnetv2:" + (dir / "espnetv2_s_2.0_city_1024x512.pth").string();
    // ESPNetv2 at 768 wide rather than its training width 1024: at KITTI size 88 instead of 151 ms a frame, so
    // a run segments 95 % of the keyframes instead of 60 %, for the same labels (KITTI 07: 2.4 % person, 92 %
    // street classes; the grey Cityscapes image 0.928 right, 0.911 at 1024).
    if (!context.colour_images && setting("width") == nullptr) resolved += ",width=768";
    for (const auto& [key, value] : p.settings) resolved += "," + key + "=" + value;
    return MakeSegmenter(resolved, context);
  }
  if (p.kind == "labels") {
    allow({"alpha", "ids"});
    need_argument("a folder (labels:DIR)");
    LabelImageSegmenter::Options options;
    if (const auto* a = setting("alpha")) options.alpha = static_cast<float>(ParseNumber(*a, "alpha"));
    if (const auto* ids = setting("ids")) {
      Require(*ids == "train" || *ids == "label", "segmenter spec: ids must be 'train' or 'label'");
      options.label_ids = *ids == "label";
    }
    return std::make_unique<LabelImageSegmenter>(p.argument, options);
  }
  if (p.kind == "truth-noisy") {
    allow({"alpha", "seed", "blobs", "blob_size"});
    need_argument("a rate (truth-noisy:RATE)");
    Require(context.truth_label_dir.has_value(),
            "segmenter spec '" + std::string(spec) + "': the sequence has no ground-truth labels (label_0/)");
    TruthNoisySegmenter::Options options;
    options.noise.rate = ParseNumber(p.argument, "rate");
    options.seed = context.seed;
    if (const auto* a = setting("alpha")) options.alpha = static_cast<float>(ParseNumber(*a, "alpha"));
    if (const auto* s = setting("seed")) options.seed = static_cast<std::uint64_t>(ParseNumber(*s, "seed"));
    if (const auto* b = setting("blobs")) options.noise.blob_fraction = ParseNumber(*b, "blobs");
    if (const auto* b = setting("blob_size")) options.noise.blob_size = ParseNumber(*b, "blob_size");
    return std::make_unique<TruthNoisySegmenter>(*context.truth_label_dir, options);
  }
  throw InvalidArgument(
      "unknown segmenter '" + std::string(spec) +
      "'; expected none, auto[:DIR], enet:FILE, espnetv2:FILE.pth, sinet:FILE.pth, onnx:CARD.yaml, "
      "labels:DIR or truth-noisy:RATE");
}

}  // namespace semslam
