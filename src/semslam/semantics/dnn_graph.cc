#include "semslam/semantics/dnn_graph.h"

#include <cmath>

#include "semslam/core/error.h"
#include "semslam/semantics/dnn_custom_layers.h"

namespace semslam {
namespace {

cv::Mat RowOf(const std::vector<float>& values) {
  return cv::Mat(1, static_cast<int>(values.size()), CV_32F, const_cast<float*>(values.data())).clone();
}

}  // namespace

DnnGraph::DnnGraph(const TorchStateDict& weights, int input_channels)
    : weights_(weights), input_channels_(input_channels) {
  RegisterCustomDnnLayers();
  net_.setInputsNames({"image"});
}

void DnnGraph::Fail(const std::string& message) const { throw InputError(weights_.source(), message); }

std::vector<std::int64_t> DnnGraph::Shape(const std::string& key) const { return weights_.Get(key).shape; }

cv::Mat DnnGraph::Weights(const std::string& key, const std::vector<std::int64_t>& shape) const {
  const TorchTensor& t = weights_.Get(key, shape);
  std::vector<int> sizes(shape.begin(), shape.end());
  if (sizes.size() == 1) sizes.insert(sizes.begin(), 1);
  cv::Mat m(static_cast<int>(sizes.size()), sizes.data(), CV_32F);
  std::copy(t.values.begin(), t.values.end(), m.ptr<float>());
  return m;
}

void DnnGraph::BatchNormFactors(const std::string& prefix, int channels, double eps,
                                std::vector<float>* scale, std::vector<float>* shift) const {
  const std::vector<std::int64_t> shape = {channels};
  const auto& gamma = weights_.Get(prefix + ".weight", shape).values;
  const auto& beta = weights_.Get(prefix + ".bias", shape).values;
  const auto& mean = weights_.Get(prefix + ".running_mean", shape).values;
  const auto& var = weights_.Get(prefix + ".running_var", shape).values;
  scale->resize(static_cast<size_t>(channels));
  shift->resize(static_cast<size_t>(channels));
  for (size_t c = 0; c < static_cast<size_t>(channels); ++c) {
    const double s = gamma[c] / std::sqrt(static_cast<double>(var[c]) + eps);
    (*scale)[c] = static_cast<float>(s);
    (*shift)[c] = static_cast<float>(beta[c] - mean[c] * s);
  }
}

DnnBlob DnnGraph::AddLayer(const std::string& type, cv::dnn::LayerParams& params,
                           const std::vector<DnnBlob>& inputs, int channels, const std::string& name_hint) {
  params.name = name_hint + "#" + std::to_string(++counter_);
  params.type = type;
  const int id = net_.addLayer(params.name, type, params);
  for (size_t i = 0; i < inputs.size(); ++i)
    net_.connect(inputs[i].layer, inputs[i].output, id, static_cast<int>(i));
  return {id, 0, channels};
}

DnnBlob DnnGraph::Conv(const DnnBlob& x, const std::string& weight_key, const ConvSpec& spec,
                       const std::string& bias_key, const std::string& bn_prefix, double bn_eps) {
  const std::vector<std::int64_t> shape = Shape(weight_key);
  if (shape.size() != 4 || spec.groups < 1 || x.channels % spec.groups != 0 || shape[0] % spec.groups != 0) {
    throw InputError(weights_.source(), "tensor '" + weight_key + "' does not fit a convolution of " +
                                            std::to_string(x.channels) + " channels in " +
                                            std::to_string(spec.groups) + " groups");
  }
  const int out = static_cast<int>(shape[0]);
  cv::Mat w = Weights(weight_key, {out, x.channels / spec.groups, shape[2], shape[3]});
  std::vector<float> bias(static_cast<size_t>(out), 0.0f);
  if (!bias_key.empty()) bias = weights_.Get(bias_key, {out}).values;
  if (!bn_prefix.empty()) {
    std::vector<float> scale, shift;
    BatchNormFactors(bn_prefix, out, bn_eps, &scale, &shift);
    const size_t per_output = w.total() / static_cast<size_t>(out);
    float* pw = w.ptr<float>();
    for (size_t o = 0; o < static_cast<size_t>(out); ++o) {
      for (size_t k = 0; k < per_output; ++k) pw[o * per_output + k] *= scale[o];
      bias[o] = bias[o] * scale[o] + shift[o];
    }
  }
  cv::dnn::LayerParams params;
  params.set("kernel_h", static_cast<int>(shape[2]));
  params.set("kernel_w", static_cast<int>(shape[3]));
  params.set("stride_h", spec.stride);
  params.set("stride_w", spec.stride);
  params.set("pad_h", spec.pad_h);
  params.set("pad_w", spec.pad_w);
  params.set("dilation_h", spec.dilation);
  params.set("dilation_w", spec.dilation);
  params.set("group", spec.groups);
  params.set("num_output", out);
  const bool has_bias = !bias_key.empty() || !bn_prefix.empty();
  params.set("bias_term", has_bias);
  params.blobs.push_back(w);
  if (has_bias) params.blobs.push_back(RowOf(bias));
  return AddLayer("Convolution", params, {x}, out, weight_key);
}

DnnBlob DnnGraph::Dense(const DnnBlob& x, const std::string& weight_key, const std::string& bias_key) {
  const std::vector<std::int64_t> shape = Shape(weight_key);
  if (shape.size() != 2)
    throw InputError(weights_.source(), "tensor '" + weight_key + "' is not a dense layer");
  const int out = static_cast<int>(shape[0]);
  cv::dnn::LayerParams params;
  params.set("kernel_size", 1);
  params.set("num_output", out);
  params.set("bias_term", true);
  params.blobs.push_back(Weights(weight_key, {out, x.channels}).reshape(1, {out, x.channels, 1, 1}));
  params.blobs.push_back(RowOf(weights_.Get(bias_key, {out}).values));
  return AddLayer("Convolution", params, {x}, out, weight_key);
}

DnnBlob DnnGraph::Deconv(const DnnBlob& x, const std::string& weight_key, int stride) {
  const std::vector<std::int64_t> shape = Shape(weight_key);
  if (shape.size() != 4)
    throw InputError(weights_.source(), "tensor '" + weight_key + "' is not a convolution");
  const int out = static_cast<int>(shape[1]);
  cv::dnn::LayerParams params;
  params.set("kernel_h", static_cast<int>(shape[2]));
  params.set("kernel_w", static_cast<int>(shape[3]));
  params.set("stride", stride);
  params.set("pad", 0);
  params.set("num_output", out);
  params.set("bias_term", false);
  params.blobs.push_back(Weights(weight_key, {x.channels, out, shape[2], shape[3]}));
  return AddLayer("Deconvolution", params, {x}, out, weight_key);
}

DnnBlob DnnGraph::BatchNorm(const DnnBlob& x, const std::string& prefix, double eps) {
  std::vector<float> scale, shift;
  BatchNormFactors(prefix, x.channels, eps, &scale, &shift);
  cv::dnn::LayerParams params;
  params.set("axis", 1);
  params.set("bias_term", true);
  params.blobs.push_back(RowOf(scale));
  params.blobs.push_back(RowOf(shift));
  return AddLayer("Scale", params, {x}, x.channels, prefix);
}

DnnBlob DnnGraph::PRelu(const DnnBlob& x, const std::string& slope_key) {
  cv::dnn::LayerParams params;
  params.blobs.push_back(RowOf(weights_.Get(slope_key, {x.channels}).values));
  return AddLayer("PReLU", params, {x}, x.channels, slope_key);
}

DnnBlob DnnGraph::Sigmoid(const DnnBlob& x) {
  cv::dnn::LayerParams params;
  return AddLayer("Sigmoid", params, {x}, x.channels, "sigmoid");
}

DnnBlob DnnGraph::Add(const DnnBlob& a, const DnnBlob& b) {
  Require(a.channels == b.channels, "DnnGraph::Add: channel counts differ");
  cv::dnn::LayerParams params;
  params.set("operation", "sum");
  return AddLayer("Eltwise", params, {a, b}, a.channels, "add");
}

DnnBlob DnnGraph::Concat(const std::vector<DnnBlob>& parts) {
  int channels = 0;
  for (const DnnBlob& p : parts) channels += p.channels;
  cv::dnn::LayerParams params;
  params.set("axis", 1);
  return AddLayer("Concat", params, parts, channels, "concat");
}

DnnBlob DnnGraph::ScaleChannels(const DnnBlob& x, const DnnBlob& gate) {
  Require(x.channels == gate.channels, "DnnGraph::ScaleChannels: channel counts differ");
  cv::dnn::LayerParams params;
  params.set("axis", 1);
  params.set("bias_term", false);
  return AddLayer("Scale", params, {x, gate}, x.channels, "scale_channels");
}

DnnBlob DnnGraph::ShuffleChannels(const DnnBlob& x, int groups) {
  Require(groups > 0 && x.channels % groups == 0, "DnnGraph::ShuffleChannels: channels not divisible");
  cv::dnn::LayerParams params;
  params.set("group", groups);
  return AddLayer("ShuffleChannel", params, {x}, x.channels, "shuffle");
}

DnnBlob DnnGraph::AvgPool(const DnnBlob& x, int kernel, int stride, int pad) {
  cv::dnn::LayerParams params;
  params.set("pool", "ave");
  params.set("kernel_size", kernel);
  params.set("stride", stride);
  params.set("pad", pad);
  params.set("ceil_mode", false);
  params.set("ave_pool_padded_area", true);
  return AddLayer("Pooling", params, {x}, x.channels, "avg_pool");
}

DnnBlob DnnGraph::GlobalAvgPool(const DnnBlob& x) {
  cv::dnn::LayerParams params;
  params.set("pool", "ave");
  params.set("global_pooling", true);
  return AddLayer("Pooling", params, {x}, x.channels, "global_avg_pool");
}

DnnBlob DnnGraph::Bilinear(const DnnBlob& x, const DnnBlob& like, bool align_corners) {
  cv::dnn::LayerParams params;
  params.set("align_corners", align_corners);
  return AddLayer(kBilinearLayer, params, {x, like}, x.channels, "bilinear");
}

DnnBlob DnnGraph::Bilinear(const DnnBlob& x, double scale, int min_size, bool align_corners) {
  cv::dnn::LayerParams params;
  params.set("align_corners", align_corners);
  params.set("scale", scale);
  params.set("min_size", min_size);
  return AddLayer(kBilinearLayer, params, {x}, x.channels, "bilinear");
}

DnnBlob DnnGraph::AdaptiveAvgPool(const DnnBlob& x, const DnnBlob& like) {
  cv::dnn::LayerParams params;
  return AddLayer(kAdaptiveAvgPoolLayer, params, {x, like}, x.channels, "adaptive_avg_pool");
}

DnnBlob DnnGraph::AdaptiveAvgPool(const DnnBlob& x, double scale, int min_size) {
  cv::dnn::LayerParams params;
  params.set("scale", scale);
  params.set("min_size", min_size);
  return AddLayer(kAdaptiveAvgPoolLayer, params, {x}, x.channels, "adaptive_avg_pool");
}

DnnBlob DnnGraph::InformationBlocking(const DnnBlob& a, const DnnBlob& b) {
  Require(a.channels == b.channels, "DnnGraph::InformationBlocking: channel counts differ");
  cv::dnn::LayerParams params;
  return AddLayer(kInformationBlockingLayer, params, {a, b}, a.channels, "information_blocking");
}

cv::dnn::Net DnnGraph::Finish() { return std::move(net_); }

}  // namespace semslam
