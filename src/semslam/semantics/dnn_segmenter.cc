#include "semslam/semantics/dnn_segmenter.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "semslam/core/error.h"
#include "semslam/semantics/torch_networks.h"
#include "semslam/semantics/torch_state_dict.h"

namespace semslam {

struct DnnSegmenter::Network {
  cv::dnn::Net net;
};

void DnnSegmenterOptions::Check() const { Require(threads >= 0, "DnnSegmenter: threads must be >= 0"); }

DnnSegmenter::DnnSegmenter(ModelCard card, Options options)
    : card_(std::move(card)), options_(options), network_(std::make_unique<Network>()) {
  card_.Check();
  options_.Check();
  if (!std::filesystem::is_regular_file(card_.file)) {
    throw InputError(card_.file,
                     "model file not found (model card '" + card_.name +
                         "'; SEMSLAM_SHARED_DATA names the folder holding segmentation_weights/)");
  }
  try {
    switch (card_.ResolvedFormat()) {
      case ModelCard::Format::kTorch:
        network_->net = cv::dnn::readNetFromTorch(card_.file.string());
        break;
      case ModelCard::Format::kPth:
        // A PyTorch state dict: the network is ours (torch_networks.h), the weights are the file's.
        network_->net = FindTorchArchitecture(card_.architecture)->build(TorchStateDict::Read(card_.file));
        break;
      default:
        network_->net = cv::dnn::readNetFromONNX(card_.file.string());
    }
  } catch (const cv::Exception& e) {
    throw InputError(card_.file, std::string("OpenCV dnn cannot load the model: ") + e.err);
  }
  if (network_->net.empty()) throw InputError(card_.file, "OpenCV dnn loaded an empty network");
  network_->net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  network_->net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
}

DnnSegmenter::~DnnSegmenter() = default;

std::string DnnSegmenter::Describe() const {
  std::ostringstream s;
  const ModelCard::Format format = card_.ResolvedFormat();
  s << "dnn " << card_.name << " (" << card_.file.string() << ", "
    << (format == ModelCard::Format::kTorch
            ? "torch"
            : (format == ModelCard::Format::kPth ? "pth " + card_.architecture : "onnx"))
    << ", input ";
  if (card_.input_width > 0 && card_.input_height == 0) {
    s << "width " << card_.input_width << ", aspect kept";
  } else if (card_.input_width > 0) {
    s << card_.input_width << "x" << card_.input_height
      << (card_.fixed_size
              ? (card_.resize == ModelCard::Resize::kTile ? " fixed, tiled" : " fixed, stretched")
              : "");
  } else {
    s << "image size";
  }
  s << ")";
  return s.str();
}

cv::Size DnnSegmenter::NetworkInputSize(cv::Size image_size) const {
  const auto round = [&](double v) {
    const int d = card_.size_divisor;
    return std::max(d, static_cast<int>(std::lround(v / d)) * d);
  };
  if (card_.input_width > 0 && card_.input_height == 0) {
    // Scaled to the card's width, aspect ratio kept.
    const double height = static_cast<double>(image_size.height) * card_.input_width / image_size.width;
    return {round(card_.input_width), round(height)};
  }
  if (card_.input_width > 0) return {card_.input_width, card_.input_height};
  return {round(image_size.width), round(image_size.height)};
}

cv::Mat DnnSegmenter::Preprocess(const cv::Mat& image) const {
  Require(!image.empty(), "DnnSegmenter: empty image");
  Require(image.depth() == CV_8U, "DnnSegmenter: expected an 8-bit image");
  cv::Mat bgr;
  switch (image.channels()) {
    case 1:
      cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
      break;
    case 3:
      bgr = image;
      break;
    case 4:
      cv::cvtColor(image, bgr, cv::COLOR_BGRA2BGR);
      break;
    default:
      throw InvalidArgument("DnnSegmenter: expected 1, 3 or 4 channels");
  }
  const cv::Size size = NetworkInputSize(image.size());
  cv::Mat resized;
  if (size == bgr.size()) {
    resized = bgr;
  } else {
    const bool shrink = size.width < bgr.cols && size.height < bgr.rows;
    cv::resize(bgr, resized, size, 0, 0, shrink ? cv::INTER_AREA : cv::INTER_LINEAR);
  }
  cv::Mat ordered;
  if (card_.rgb) {
    cv::cvtColor(resized, ordered, cv::COLOR_BGR2RGB);
  } else {
    ordered = resized;
  }
  // x = (pixel * scale - mean) / std, channel by channel in the network's order.
  cv::Mat normalized;
  ordered.convertTo(normalized, CV_32FC3, card_.scale);
  normalized -= cv::Scalar(card_.mean[0], card_.mean[1], card_.mean[2]);
  cv::multiply(normalized, cv::Scalar(1.0 / card_.stddev[0], 1.0 / card_.stddev[1], 1.0 / card_.stddev[2]),
               normalized);
  return cv::dnn::blobFromImage(normalized, 1.0, cv::Size(), cv::Scalar(), false, false, CV_32F);
}

cv::Mat DnnSegmenter::Forward(const cv::Mat& image) {
  const cv::Mat blob = Preprocess(image);
  if (options_.threads > 0) cv::setNumThreads(options_.threads);
  try {
    network_->net.setInput(blob);
    return card_.output_name.empty() ? network_->net.forward() : network_->net.forward(card_.output_name);
  } catch (const cv::Exception& e) {
    throw InputError(card_.file, std::string("forward pass failed: ") + e.err);
  }
}

namespace {

std::vector<int> OutputShape(const cv::Mat& output) {
  std::vector<int> shape(output.size.p, output.size.p + output.dims);
  // Drop a leading batch dimension of 1.
  if (!shape.empty() && shape.front() == 1 && shape.size() >= 3) shape.erase(shape.begin());
  return shape;
}

std::string ShapeText(const std::vector<int>& shape) {
  std::string s;
  for (int d : shape) s += (s.empty() ? "" : "x") + std::to_string(d);
  return s;
}

// Per-channel probabilities (normalized over the channels) from score planes.
std::vector<cv::Mat> ToProbabilities(const std::vector<cv::Mat>& planes, ScoreKind kind) {
  std::vector<cv::Mat> p(planes.size());
  cv::Mat sum = cv::Mat::zeros(planes[0].size(), CV_32FC1);
  cv::Mat max_score;
  if (kind == ScoreKind::kLogits) {
    max_score = planes[0].clone();
    for (size_t c = 1; c < planes.size(); ++c) cv::max(max_score, planes[c], max_score);
  }
  for (size_t c = 0; c < planes.size(); ++c) {
    if (kind == ScoreKind::kLogits) {
      cv::exp(planes[c] - max_score, p[c]);
    } else if (kind == ScoreKind::kLogProbabilities) {
      cv::exp(planes[c], p[c]);
    } else {
      p[c] = cv::max(planes[c], 0.0);
    }
    sum += p[c];
  }
  cv::max(sum, 1e-30, sum);
  for (cv::Mat& plane : p) cv::divide(plane, sum, plane);
  return p;
}

}  // namespace

std::vector<cv::Mat> DnnSegmenter::ScorePlanes(cv::Mat& output) const {
  const size_t num_channels = card_.channel_to_train_id.size();
  const std::vector<int> shape = OutputShape(output);
  if (output.depth() != CV_32F || shape.size() != 3) {
    throw InputError(card_.file,
                     "output of shape " + ShapeText(shape) + ", expected 1xCxHxW or 1xHxWxC float scores");
  }
  std::vector<cv::Mat> planes;
  if (card_.layout == ModelCard::Layout::kNchw) {
    if (static_cast<size_t>(shape[0]) != num_channels) {
      throw InputError(card_.file, "output has " + std::to_string(shape[0]) +
                                       " channels but the model card lists " + std::to_string(num_channels) +
                                       " classes");
    }
    float* data = output.ptr<float>();
    const size_t plane_size = static_cast<size_t>(shape[1]) * static_cast<size_t>(shape[2]);
    for (size_t c = 0; c < num_channels; ++c)
      planes.emplace_back(shape[1], shape[2], CV_32FC1, data + c * plane_size);
  } else {
    if (static_cast<size_t>(shape[2]) != num_channels) {
      throw InputError(card_.file, "output has " + std::to_string(shape[2]) +
                                       " channels but the model card lists " + std::to_string(num_channels) +
                                       " classes");
    }
    cv::Mat interleaved(shape[0], shape[1], CV_32FC(static_cast<int>(num_channels)), output.ptr<float>());
    cv::split(interleaved, planes);
  }
  return planes;
}

std::vector<cv::Mat> DnnSegmenter::KeptPlanes(cv::Mat& output) const {
  std::vector<cv::Mat> planes = ScorePlanes(output);
  std::vector<cv::Mat> kept;
  for (size_t c = 0; c < planes.size(); ++c) {
    if (card_.channel_to_train_id[c] != kDropChannel) kept.push_back(planes[c]);
  }
  return kept;
}

Segmentation DnnSegmenter::Segment(const cv::Mat& image, std::int64_t /*frame_index*/) {
  Require(!image.empty(), "DnnSegmenter: empty image");
  std::vector<std::uint8_t> kept_ids;
  for (std::uint8_t id : card_.channel_to_train_id) {
    if (id != kDropChannel) kept_ids.push_back(id);
  }
  const size_t num_channels = kept_ids.size();
  const cv::Size net_size(card_.input_width, card_.input_height);
  const int tiled_width =
      card_.resize == ModelCard::Resize::kTile
          ? static_cast<int>(std::lround(image.cols * static_cast<double>(net_size.height) / image.rows))
          : 0;
  if (tiled_width > net_size.width) {
    // Keep the aspect ratio: scale to the network's height, run overlapping windows across, average.
    cv::Mat scaled;
    cv::resize(image, scaled, cv::Size(tiled_width, net_size.height), 0, 0,
               net_size.height < image.rows ? cv::INTER_AREA : cv::INTER_LINEAR);
    const int windows = (tiled_width + net_size.width - 1) / net_size.width;
    std::vector<cv::Mat> sum;
    cv::Mat count;
    double out_scale = 1.0;
    for (int w = 0; w < windows; ++w) {
      const int x0 = static_cast<int>(
          std::lround(static_cast<double>(w) * (tiled_width - net_size.width) / std::max(windows - 1, 1)));
      cv::Mat output = Forward(scaled.colRange(x0, x0 + net_size.width));
      const std::vector<cv::Mat> p = ToProbabilities(KeptPlanes(output), card_.scores);
      if (sum.empty()) {
        out_scale = static_cast<double>(p[0].cols) / net_size.width;
        const cv::Size out_size(static_cast<int>(std::lround(tiled_width * out_scale)), p[0].rows);
        sum.assign(num_channels, cv::Mat());
        for (cv::Mat& m : sum) m = cv::Mat::zeros(out_size, CV_32FC1);
        count = cv::Mat::zeros(1, out_size.width, CV_32FC1);
      }
      const int ox = std::min(static_cast<int>(std::lround(x0 * out_scale)), sum[0].cols - p[0].cols);
      for (size_t c = 0; c < num_channels; ++c) sum[c].colRange(ox, ox + p[c].cols) += p[c];
      count.colRange(ox, ox + p[0].cols) += 1.0f;
    }
    const cv::Mat inverse_count = 1.0 / cv::max(count, 1.0f);
    for (cv::Mat& m : sum) {
      m = m.mul(cv::repeat(inverse_count, m.rows, 1));
      // Never store more cells than the image has pixels.
      if (m.cols > image.cols && m.rows > image.rows) cv::resize(m, m, image.size(), 0, 0, cv::INTER_AREA);
    }
    return SegmentationFromScores(sum, ScoreKind::kProbabilities, kept_ids, image.size());
  }

  cv::Mat output = Forward(image);
  if (card_.layout == ModelCard::Layout::kLabels) {
    std::vector<int> shape = OutputShape(output);
    if (shape.size() == 3 && shape[0] == 1) shape.erase(shape.begin());
    if (shape.size() != 2) {
      throw InputError(card_.file, "label output of shape " + ShapeText(shape) + ", expected HxW");
    }
    cv::Mat indices(shape[0], shape[1], CV_32SC1);
    cv::Mat(shape[0], shape[1], output.type(), output.data).convertTo(indices, CV_32SC1);
    cv::Mat labels(indices.size(), CV_8UC1);
    for (int y = 0; y < labels.rows; ++y) {
      const int* in = indices.ptr<int>(y);
      std::uint8_t* out = labels.ptr<std::uint8_t>(y);
      for (int x = 0; x < labels.cols; ++x) {
        out[x] = (in[x] >= 0 && static_cast<size_t>(in[x]) < num_channels)
                     ? card_.channel_to_train_id[static_cast<size_t>(in[x])]
                     : kNoLabel;
      }
    }
    return Segmentation::FromLabels(labels, image.size(), 1.0f);
  }
  return SegmentationFromScores(KeptPlanes(output), card_.scores, kept_ids, image.size());
}

}  // namespace semslam
