#include "semslam/semantics/semantic_outputs.h"

#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>

#include "semslam/core/atomic_file.h"
#include "semslam/core/error.h"

namespace semslam {
namespace {

static_assert(std::endian::native == std::endian::little, "the PLY writer assumes a little-endian machine");

template <typename T>
void PutBinary(std::string& out, T value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

struct PlyProperty {
  std::string name;
  std::string type;
  size_t size = 0;
};

size_t PlyTypeSize(const std::string& type) {
  static const std::map<std::string, size_t> sizes = {
      {"char", 1},  {"uchar", 1},   {"int8", 1},   {"uint8", 1},  {"short", 2}, {"ushort", 2},
      {"int16", 2}, {"uint16", 2},  {"int", 4},    {"uint", 4},   {"int32", 4}, {"uint32", 4},
      {"float", 4}, {"float32", 4}, {"double", 8}, {"float64", 8}};
  const auto it = sizes.find(type);
  return it == sizes.end() ? 0 : it->second;
}

double ReadBinaryValue(const char* p, const std::string& type) {
  const auto get = [p]<typename T>(T) {
    T v;
    std::memcpy(&v, p, sizeof(T));
    return static_cast<double>(v);
  };
  if (type == "char" || type == "int8") return get(std::int8_t{});
  if (type == "uchar" || type == "uint8") return get(std::uint8_t{});
  if (type == "short" || type == "int16") return get(std::int16_t{});
  if (type == "ushort" || type == "uint16") return get(std::uint16_t{});
  if (type == "int" || type == "int32") return get(std::int32_t{});
  if (type == "uint" || type == "uint32") return get(std::uint32_t{});
  if (type == "float" || type == "float32") return get(float{});
  return get(double{});
}

void Assign(SemanticPoint& point, const std::string& name, double value) {
  if (name == "x")
    point.position.x() = value;
  else if (name == "y")
    point.position.y() = value;
  else if (name == "z")
    point.position.z() = value;
  else if (name == "label")
    point.label = static_cast<int>(value);
  else if (name == "confidence")
    point.confidence = static_cast<float>(value);
  else if (name == "observations")
    point.observations = static_cast<int>(value);
}

}  // namespace

SemanticPoint ToSemanticPoint(const Eigen::Vector3d& position, const LabelDistribution& labels) {
  SemanticPoint p;
  p.position = position;
  p.label = labels.Label();
  p.confidence = labels.HasObservations() ? labels.Confidence() : 0.0f;
  p.observations = labels.NumObservations();
  return p;
}

void WriteSemanticPly(const std::filesystem::path& path, std::span<const SemanticPoint> points,
                      PlyFormat format) {
  std::string out;
  out.reserve(300 + points.size() * (format == PlyFormat::kBinary ? 24 : 64));
  out += "ply\n";
  out += format == PlyFormat::kBinary ? "format binary_little_endian 1.0\n" : "format ascii 1.0\n";
  out += "comment semslam semantic map: label = Cityscapes trainId (255 = none), colour = class palette\n";
  out += "element vertex " + std::to_string(points.size()) + "\n";
  out += "property float x\nproperty float y\nproperty float z\n";
  out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  out += "property uchar label\nproperty float confidence\nproperty int observations\n";
  out += "end_header\n";
  char line[256];
  for (const SemanticPoint& p : points) {
    Require(p.position.allFinite(), "WriteSemanticPly: non-finite point position");
    const std::uint8_t label = IsValidTrainId(p.label) ? static_cast<std::uint8_t>(p.label) : kNoLabel;
    const Rgb color = ClassColor(label);
    if (format == PlyFormat::kBinary) {
      PutBinary(out, static_cast<float>(p.position.x()));
      PutBinary(out, static_cast<float>(p.position.y()));
      PutBinary(out, static_cast<float>(p.position.z()));
      PutBinary(out, color.r);
      PutBinary(out, color.g);
      PutBinary(out, color.b);
      PutBinary(out, label);
      PutBinary(out, p.confidence);
      PutBinary(out, static_cast<std::int32_t>(p.observations));
    } else {
      const int n = std::snprintf(line, sizeof(line), "%.9g %.9g %.9g %u %u %u %u %.7g %d\n",
                                  static_cast<float>(p.position.x()), static_cast<float>(p.position.y()),
                                  static_cast<float>(p.position.z()), unsigned{color.r}, unsigned{color.g},
                                  unsigned{color.b}, unsigned{label}, static_cast<double>(p.confidence),
                                  p.observations);
      out.append(line, static_cast<size_t>(n));
    }
  }
  WriteFileAtomically(path, out);
}

std::vector<SemanticPoint> ReadSemanticPly(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open the PLY file");
  std::string line;
  int line_number = 0;
  const auto fail = [&](const std::string& message) -> void {
    throw InputError(SourceLocation{path, line_number}, message);
  };
  if (!std::getline(in, line) || line != "ply") {
    ++line_number;
    fail("not a PLY file");
  }
  ++line_number;
  bool binary = false;
  size_t vertices = 0;
  bool in_vertex = false, seen_vertex = false;
  std::vector<PlyProperty> properties;
  for (;;) {
    if (!std::getline(in, line)) fail("unexpected end of the header");
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (keyword == "end_header") break;
    if (keyword == "comment" || keyword == "obj_info" || keyword.empty()) continue;
    if (keyword == "format") {
      std::string kind;
      words >> kind;
      if (kind == "binary_little_endian") {
        binary = true;
      } else if (kind != "ascii") {
        fail("unsupported PLY format '" + kind + "'");
      }
    } else if (keyword == "element") {
      std::string name;
      long long count = -1;
      words >> name >> count;
      if (seen_vertex) fail("elements after 'vertex' are not supported");
      in_vertex = name == "vertex";
      if (!in_vertex) fail("only a 'vertex' element is supported, found '" + name + "'");
      if (count < 0) fail("bad vertex count");
      vertices = static_cast<size_t>(count);
      seen_vertex = true;
    } else if (keyword == "property") {
      PlyProperty property;
      words >> property.type >> property.name;
      if (property.type == "list") fail("list properties are not supported");
      property.size = PlyTypeSize(property.type);
      if (property.size == 0) fail("unknown property type '" + property.type + "'");
      properties.push_back(property);
    } else {
      fail("unknown header line '" + line + "'");
    }
  }
  std::vector<SemanticPoint> points(vertices);
  if (binary) {
    size_t stride = 0;
    for (const auto& p : properties) stride += p.size;
    std::string record(stride, '\0');
    for (size_t i = 0; i < vertices; ++i) {
      if (!in.read(record.data(), static_cast<std::streamsize>(stride))) {
        throw InputError(path, "truncated binary data at vertex " + std::to_string(i));
      }
      size_t offset = 0;
      for (const auto& p : properties) {
        Assign(points[i], p.name, ReadBinaryValue(record.data() + offset, p.type));
        offset += p.size;
      }
    }
  } else {
    for (size_t i = 0; i < vertices; ++i) {
      if (!std::getline(in, line)) fail("expected " + std::to_string(vertices) + " vertices");
      ++line_number;
      std::istringstream values(line);
      for (const auto& p : properties) {
        double v = 0.0;
        if (!(values >> v)) fail("property '" + p.name + "': not a number");
        Assign(points[i], p.name, v);
      }
    }
  }
  for (auto& p : points) {
    if (!p.position.allFinite()) throw InputError(path, "non-finite point position");
    if (!IsValidTrainId(p.label)) p.label = kNoLabel;
  }
  return points;
}

ClassCounts CountLabels(std::span<const SemanticPoint> points) {
  ClassCounts counts{};
  for (const auto& p : points) ++counts[IsValidTrainId(p.label) ? static_cast<size_t>(p.label) : kNumClasses];
  return counts;
}

ClassCounts CountLabels(const cv::Mat& train_ids) {
  Require(train_ids.type() == CV_8UC1, "CountLabels: expected CV_8U trainIds");
  ClassCounts counts{};
  for (int y = 0; y < train_ids.rows; ++y) {
    const std::uint8_t* row = train_ids.ptr<std::uint8_t>(y);
    for (int x = 0; x < train_ids.cols; ++x) ++counts[row[x] < kNumClasses ? row[x] : kNumClasses];
  }
  return counts;
}

std::optional<double> LabelAccuracy::ClassAccuracy(int train_id) const {
  if (!IsValidTrainId(train_id) || class_evaluated[static_cast<size_t>(train_id)] == 0) return std::nullopt;
  return static_cast<double>(class_correct[static_cast<size_t>(train_id)]) /
         static_cast<double>(class_evaluated[static_cast<size_t>(train_id)]);
}

LabelAccuracy EvaluatePointLabels(std::span<const SemanticPoint> points, const GroundTruthClassFn& truth) {
  Require(static_cast<bool>(truth), "EvaluatePointLabels: no ground-truth function");
  LabelAccuracy accuracy;
  for (const auto& p : points) {
    const std::optional<int> t = truth(p.position);
    if (!t || !IsValidTrainId(*t)) {
      ++accuracy.no_truth;
      continue;
    }
    if (!IsValidTrainId(p.label)) {
      ++accuracy.unlabeled;
      continue;
    }
    ++accuracy.evaluated;
    ++accuracy.class_evaluated[static_cast<size_t>(*t)];
    if (p.label == *t) {
      ++accuracy.correct;
      ++accuracy.class_correct[static_cast<size_t>(*t)];
    }
  }
  return accuracy;
}

void SegmentationScore::Add(const cv::Mat& predicted, const cv::Mat& truth) {
  Require(predicted.type() == CV_8UC1 && truth.type() == CV_8UC1,
          "SegmentationScore: expected CV_8U trainIds");
  Require(predicted.size() == truth.size(), "SegmentationScore: prediction and truth differ in size");
  for (int y = 0; y < truth.rows; ++y) {
    const std::uint8_t* t = truth.ptr<std::uint8_t>(y);
    const std::uint8_t* p = predicted.ptr<std::uint8_t>(y);
    for (int x = 0; x < truth.cols; ++x) {
      if (t[x] >= kNumClasses) continue;
      const size_t predicted_class = p[x] < kNumClasses ? p[x] : kNumClasses;
      ++confusion_[t[x]][predicted_class];
      ++pixels_;
      if (predicted_class == t[x]) ++correct_;
    }
  }
}

double SegmentationScore::PixelAccuracy() const {
  return pixels_ ? static_cast<double>(correct_) / static_cast<double>(pixels_) : 0.0;
}

std::uint64_t SegmentationScore::Count(int truth, int predicted) const {
  if (!IsValidTrainId(truth) || predicted < 0 || predicted > kNumClasses) return 0;
  return confusion_[static_cast<size_t>(truth)][static_cast<size_t>(predicted)];
}

std::optional<double> SegmentationScore::ClassIou(int train_id) const {
  if (!IsValidTrainId(train_id)) return std::nullopt;
  const auto c = static_cast<size_t>(train_id);
  const std::uint64_t tp = confusion_[c][c];
  std::uint64_t fn = 0, fp = 0;
  for (size_t p = 0; p <= kNumClasses; ++p) fn += p == c ? 0 : confusion_[c][p];
  for (size_t t = 0; t < kNumClasses; ++t) fp += t == c ? 0 : confusion_[t][c];
  const std::uint64_t union_count = tp + fn + fp;
  if (union_count == 0) return std::nullopt;
  return static_cast<double>(tp) / static_cast<double>(union_count);
}

double SegmentationScore::MeanIou() const {
  double sum = 0.0;
  int n = 0;
  for (int c = 0; c < kNumClasses; ++c) {
    if (const auto iou = ClassIou(c)) {
      sum += *iou;
      ++n;
    }
  }
  return n ? sum / n : 0.0;
}

double SegmentationScore::MeanIouOverTruthClasses() const {
  double sum = 0.0;
  int n = 0;
  for (int c = 0; c < kNumClasses; ++c) {
    std::uint64_t in_truth = 0;
    for (auto v : confusion_[static_cast<size_t>(c)]) in_truth += v;
    if (in_truth == 0) continue;
    sum += ClassIou(c).value_or(0.0);
    ++n;
  }
  return n ? sum / n : 0.0;
}

cv::Mat ColorizeLabels(const cv::Mat& train_ids, const cv::Mat& image, double alpha) {
  Require(train_ids.type() == CV_8UC1, "ColorizeLabels: expected CV_8U trainIds");
  cv::Mat lut(1, 256, CV_8UC3, cv::Scalar(0, 0, 0));
  for (int c = 0; c < kNumClasses; ++c) {
    const Rgb rgb = ClassColor(c);
    lut.at<cv::Vec3b>(0, c) = cv::Vec3b(rgb.b, rgb.g, rgb.r);
  }
  cv::Mat colored;
  cv::Mat ids3;
  cv::cvtColor(train_ids, ids3, cv::COLOR_GRAY2BGR);
  cv::LUT(ids3, lut, colored);
  if (image.empty()) return colored;
  Require(image.size() == train_ids.size(), "ColorizeLabels: image and labels differ in size");
  Require(std::isfinite(alpha) && alpha >= 0.0 && alpha <= 1.0, "ColorizeLabels: alpha must lie in [0, 1]");
  cv::Mat base;
  if (image.channels() == 1) {
    cv::cvtColor(image, base, cv::COLOR_GRAY2BGR);
  } else if (image.channels() == 4) {
    cv::cvtColor(image, base, cv::COLOR_BGRA2BGR);
  } else {
    base = image;
  }
  cv::Mat blended;
  cv::addWeighted(colored, alpha, base, 1.0 - alpha, 0.0, blended);
  return blended;
}

}  // namespace semslam
