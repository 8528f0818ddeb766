#include "semslam/semantics/model_card.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "semslam/core/error.h"
#include "semslam/core/yaml_file.h"
#include "semslam/semantics/class_table.h"
#include "semslam/semantics/torch_networks.h"

namespace semslam {
namespace {

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

class CardParser {
 public:
  explicit CardParser(std::filesystem::path source) : source_(std::move(source)) {}

  [[noreturn]] void Fail(const YAML::Node& node, const std::string& field, const std::string& message) const {
    const int line = node.IsDefined() && node.Mark().line >= 0 ? node.Mark().line + 1 : 0;
    throw InputError(SourceLocation{source_, line}, field, message);
  }

  template <typename T>
  T Get(const YAML::Node& node, const std::string& field) const {
    try {
      return node.as<T>();
    } catch (const YAML::Exception&) {
      Fail(node, field, "has the wrong type");
    }
  }

  double GetFinite(const YAML::Node& node, const std::string& field) const {
    const double v = Get<double>(node, field);
    if (!std::isfinite(v)) Fail(node, field, "must be a finite number");
    return v;
  }

  std::array<double, 3> GetTriple(const YAML::Node& node, const std::string& field) const {
    if (node.IsScalar()) {
      const double v = GetFinite(node, field);
      return {v, v, v};
    }
    if (!node.IsSequence() || node.size() != 3) Fail(node, field, "must be a number or a list of 3 numbers");
    return {GetFinite(node[0], field), GetFinite(node[1], field), GetFinite(node[2], field)};
  }

  std::uint8_t ClassOf(const YAML::Node& node, const std::string& field) const {
    const std::string text = Get<std::string>(node, field);
    const std::string lower = Lower(text);
    if (lower == "none" || lower == "unlabeled" || lower == "ignore" || lower == "-1" || lower == "255") {
      return kNoLabel;
    }
    if (lower == "drop") return kDropChannel;
    char* end = nullptr;
    const long id = std::strtol(text.c_str(), &end, 10);
    if (end != text.c_str() && *end == '\0') {
      if (!IsValidTrainId(static_cast<int>(id))) Fail(node, field, "trainId " + text + " is not in 0..18");
      return static_cast<std::uint8_t>(id);
    }
    const auto named = TrainIdFromName(text);
    if (!named) Fail(node, field, "unknown class '" + text + "'");
    return static_cast<std::uint8_t>(*named);
  }

 private:
  std::filesystem::path source_;
};

std::vector<std::uint8_t> CityscapesIdentity() {
  std::vector<std::uint8_t> ids(kNumClasses);
  for (int c = 0; c < kNumClasses; ++c) ids[static_cast<size_t>(c)] = static_cast<std::uint8_t>(c);
  return ids;
}

}  // namespace

std::string ExpandEnvironment(const std::string& text) {
  std::string out;
  size_t i = 0;
  while (i < text.size()) {
    if (text.compare(i, 2, "${") != 0) {
      out.push_back(text[i++]);
      continue;
    }
    const size_t close = text.find('}', i + 2);
    Require(close != std::string::npos, "unterminated ${...} in '" + text + "'");
    const std::string inner = text.substr(i + 2, close - i - 2);
    const size_t dash = inner.find(":-");
    const std::string name = inner.substr(0, dash);
    const char* value = std::getenv(name.c_str());
    if (value != nullptr && *value != '\0') {
      out += value;
    } else {
      Require(dash != std::string::npos, "environment variable " + name + " is not set (in '" + text + "')");
      out += inner.substr(dash + 2);
    }
    i = close + 1;
  }
  return out;
}

void ModelCard::Check() const {
  Require(!file.empty(), "model card: 'file' is empty");
  Require(input_width >= 0 && input_height >= 0 && (input_width > 0 || input_height == 0),
          "model card: input width and height must both be positive, width alone, or both absent");
  Require(input_height > 0 || input_width == 0 || !fixed_size, "model card: a fixed input needs a height");
  Require(!fixed_size || input_width > 0, "model card: a fixed input needs width and height");
  Require(resize == Resize::kStretch || fixed_size, "model card: resize: tile needs a fixed input size");
  Require(resize == Resize::kStretch || layout != Layout::kLabels,
          "model card: resize: tile needs score outputs");
  Require(size_divisor >= 1, "model card: size_divisor must be >= 1");
  Require(std::isfinite(scale) && scale > 0.0, "model card: scale must be > 0");
  for (int c = 0; c < 3; ++c) {
    Require(std::isfinite(mean[static_cast<size_t>(c)]), "model card: mean must be finite");
    Require(std::isfinite(stddev[static_cast<size_t>(c)]) && stddev[static_cast<size_t>(c)] > 0.0,
            "model card: std must be > 0");
  }
  Require(!channel_to_train_id.empty(), "model card: no output classes");
  for (std::uint8_t id : channel_to_train_id) {
    Require(id < kNumClasses || id == kNoLabel || id == kDropChannel,
            "model card: class ids must be trainIds, none or drop");
  }
  Require(layout != Layout::kLabels || std::find(channel_to_train_id.begin(), channel_to_train_id.end(),
                                                 kDropChannel) == channel_to_train_id.end(),
          "model card: a label output cannot drop classes");
  bool pth = format == Format::kPth;
  if (format == Format::kAuto) {
    const std::string ext = Lower(file.extension().string());
    pth = ext == ".pth" || ext == ".pt";
  }
  if (pth) {
    const TorchArchitecture* a = FindTorchArchitecture(architecture);
    Require(a != nullptr, "model card: a .pth state dict needs architecture: espnetv2 or sinet (got '" +
                              architecture + "')");
    Require(size_divisor % a->size_divisor == 0, "model card: size_divisor must be a multiple of " +
                                                     std::to_string(a->size_divisor) + " for " +
                                                     architecture);
    Require(input_height == 0 || (input_width % a->size_divisor == 0 && input_height % a->size_divisor == 0),
            "model card: input width and height must be multiples of " + std::to_string(a->size_divisor) +
                " for " + architecture);
  }
}

ModelCard::Format ModelCard::ResolvedFormat() const {
  if (format != Format::kAuto) return format;
  const std::string ext = Lower(file.extension().string());
  if (ext == ".onnx") return Format::kOnnx;
  if (ext == ".net" || ext == ".t7" || ext == ".th") return Format::kTorch;
  if (ext == ".pth" || ext == ".pt") return Format::kPth;
  throw InvalidArgument("model card: cannot tell the format of '" + file.string() +
                        "' from its extension; set format: torch|onnx|pth");
}

ModelCard ParseModelCard(const std::string& yaml, const std::filesystem::path& base_dir,
                         const std::filesystem::path& source) {
  CardParser p(source);
  const YAML::Node root = LoadYamlText(yaml, source);
  if (!root.IsMap()) throw InputError(source, "a model card must be a YAML map");
  ModelCard card;
  card.name = root["name"] ? p.Get<std::string>(root["name"], "name") : source.stem().string();

  if (!root["file"]) throw InputError(source, "missing field 'file'");
  std::string file_text;
  try {
    file_text = ExpandEnvironment(p.Get<std::string>(root["file"], "file"));
  } catch (const InvalidArgument& e) {
    p.Fail(root["file"], "file", e.what());
  }
  card.file = file_text;
  if (card.file.is_relative()) card.file = (base_dir / card.file).lexically_normal();

  if (root["format"]) {
    const std::string f = Lower(p.Get<std::string>(root["format"], "format"));
    if (f == "torch") {
      card.format = ModelCard::Format::kTorch;
    } else if (f == "onnx") {
      card.format = ModelCard::Format::kOnnx;
    } else if (f == "pth" || f == "pytorch") {
      card.format = ModelCard::Format::kPth;
    } else if (f == "auto") {
      card.format = ModelCard::Format::kAuto;
    } else {
      p.Fail(root["format"], "format", "must be torch, onnx, pth or auto");
    }
  }
  if (root["architecture"])
    card.architecture = Lower(p.Get<std::string>(root["architecture"], "architecture"));
  if (const TorchArchitecture* a = FindTorchArchitecture(card.architecture))
    card.size_divisor = a->size_divisor;

  if (const YAML::Node input = root["input"]) {
    if (!input.IsMap()) p.Fail(input, "input", "must be a map");
    if (input["width"]) card.input_width = p.Get<int>(input["width"], "input.width");
    if (input["height"]) card.input_height = p.Get<int>(input["height"], "input.height");
    if (input["fixed"]) card.fixed_size = p.Get<bool>(input["fixed"], "input.fixed");
    if (input["resize"]) {
      const std::string resize = Lower(p.Get<std::string>(input["resize"], "input.resize"));
      if (resize != "stretch" && resize != "tile")
        p.Fail(input["resize"], "input.resize", "must be stretch or tile");
      card.resize = resize == "tile" ? ModelCard::Resize::kTile : ModelCard::Resize::kStretch;
    }
    if (input["size_divisor"]) card.size_divisor = p.Get<int>(input["size_divisor"], "input.size_divisor");
    if (input["channel_order"]) {
      const std::string order = Lower(p.Get<std::string>(input["channel_order"], "input.channel_order"));
      if (order != "rgb" && order != "bgr")
        p.Fail(input["channel_order"], "input.channel_order", "must be rgb or bgr");
      card.rgb = order == "rgb";
    }
    if (input["scale"]) card.scale = p.GetFinite(input["scale"], "input.scale");
    if (input["mean"]) card.mean = p.GetTriple(input["mean"], "input.mean");
    if (input["std"]) card.stddev = p.GetTriple(input["std"], "input.std");
    if (card.input_width < 0 || card.input_height < 0)
      p.Fail(input, "input", "width and height must be >= 0");
  }

  card.channel_to_train_id = CityscapesIdentity();
  if (const YAML::Node output = root["output"]) {
    if (!output.IsMap()) p.Fail(output, "output", "must be a map");
    if (output["name"]) card.output_name = p.Get<std::string>(output["name"], "output.name");
    if (output["layout"]) {
      const std::string layout = Lower(p.Get<std::string>(output["layout"], "output.layout"));
      if (layout == "nchw") {
        card.layout = ModelCard::Layout::kNchw;
      } else if (layout == "nhwc") {
        card.layout = ModelCard::Layout::kNhwc;
      } else if (layout == "labels") {
        card.layout = ModelCard::Layout::kLabels;
      } else {
        p.Fail(output["layout"], "output.layout", "must be nchw, nhwc or labels");
      }
    }
    if (output["scores"]) {
      const std::string scores = Lower(p.Get<std::string>(output["scores"], "output.scores"));
      if (scores == "logits") {
        card.scores = ScoreKind::kLogits;
      } else if (scores == "probabilities") {
        card.scores = ScoreKind::kProbabilities;
      } else if (scores == "log_probabilities") {
        card.scores = ScoreKind::kLogProbabilities;
      } else {
        p.Fail(output["scores"], "output.scores", "must be logits, probabilities or log_probabilities");
      }
    }
    if (const YAML::Node classes = output["classes"]) {
      if (classes.IsScalar()) {
        if (Lower(p.Get<std::string>(classes, "output.classes")) != "cityscapes") {
          p.Fail(classes, "output.classes", "must be 'cityscapes' or a list of classes");
        }
      } else if (classes.IsSequence() && classes.size() > 0) {
        card.channel_to_train_id.clear();
        for (const YAML::Node& c : classes)
          card.channel_to_train_id.push_back(p.ClassOf(c, "output.classes"));
      } else {
        p.Fail(classes, "output.classes", "must be 'cityscapes' or a non-empty list of classes");
      }
    }
  }
  try {
    card.Check();
  } catch (const InvalidArgument& e) {
    throw InputError(source, e.what());
  }
  return card;
}

ModelCard ReadModelCard(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot open the model card");
  std::stringstream text;
  text << in.rdbuf();
  return ParseModelCard(text.str(), std::filesystem::absolute(path).parent_path(), path);
}

namespace {

ModelCard TorchCityscapesCard(const std::string& name, const std::string& architecture,
                              const std::filesystem::path& weights, int width) {
  ModelCard card;
  card.name = name;
  card.file = weights;
  card.format = ModelCard::Format::kPth;
  card.architecture = architecture;
  card.input_width = width;
  card.size_divisor = FindTorchArchitecture(architecture)->size_divisor;
  card.rgb = true;
  card.scale = 1.0 / 255.0;
  card.mean = {0.485, 0.456, 0.406};
  card.stddev = {0.229, 0.224, 0.225};
  card.layout = ModelCard::Layout::kNchw;
  card.scores = ScoreKind::kLogits;
  card.channel_to_train_id = CityscapesIdentity();
  return card;
}

}  // namespace

ModelCard EspNetV2CityscapesCard(const std::filesystem::path& weights, int width) {
  ModelCard card = TorchCityscapesCard("espnetv2-cityscapes", "espnetv2", weights, width > 0 ? width : 1024);
  card.channel_to_train_id.push_back(kDropChannel);  // background
  return card;
}

ModelCard SiNetCityscapesCard(const std::filesystem::path& weights, int width) {
  return TorchCityscapesCard("sinet-cityscapes", "sinet", weights, width > 0 ? width : 1280);
}

ModelCard EnetCityscapesCard(const std::filesystem::path& weights) {
  ModelCard card;
  card.name = "enet-cityscapes";
  card.file = weights;
  card.format = ModelCard::Format::kTorch;
  card.input_width = 1024;
  card.input_height = 512;
  card.fixed_size = true;
  card.rgb = true;
  card.scale = 1.0 / 255.0;
  card.layout = ModelCard::Layout::kNchw;
  card.scores = ScoreKind::kLogits;
  card.channel_to_train_id.push_back(kNoLabel);
  for (int c = 0; c < kNumClasses; ++c) card.channel_to_train_id.push_back(static_cast<std::uint8_t>(c));
  return card;
}

}  // namespace semslam
