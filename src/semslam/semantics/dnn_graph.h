#pragma once
// Builds an OpenCV dnn network in C++ (cv::dnn::Net::addLayer/connect) from the tensors of a PyTorch state
// dict, layer by layer, with the state dict's names: the networks of torch_networks.h are written with it.
// Every weight is looked up by name with the shape the layer needs, so a state dict of another network fails
// with an InputError naming the tensor. Batch norms that directly follow a convolution are folded into it;
// the others become per-channel scale-and-shift layers.

#include <opencv2/dnn.hpp>
#include <string>
#include <vector>

#include "semslam/semantics/torch_state_dict.h"

namespace semslam {

// A blob in the network under construction: the layer that makes it, which output, and its channel count.
struct DnnBlob {
  int layer = 0;  // 0: the network input
  int output = 0;
  int channels = 0;
};

struct ConvSpec {
  int stride = 1;
  int pad_h = 0, pad_w = 0;
  int dilation = 1;
  int groups = 1;
};

class DnnGraph {
 public:
  // `input_channels`: channels of the network input (3 for an RGB image).
  DnnGraph(const TorchStateDict& weights, int input_channels);

  DnnBlob input() const { return {0, 0, input_channels_}; }

  // Convolution with the weights `weight_key` (out x in/groups x kh x kw; `out` and the kernel are taken from
  // the state dict, `in` must be the blob's channels), an optional bias `bias_key`, and an optional batch
  // norm `bn_prefix` (.weight/.bias/.running_mean/.running_var) folded in.
  DnnBlob Conv(const DnnBlob& x, const std::string& weight_key, const ConvSpec& spec,
               const std::string& bias_key = "", const std::string& bn_prefix = "", double bn_eps = 1e-5);
  // A fully connected layer (out x in weights, bias) on a 1x1 blob, as a 1x1 convolution.
  DnnBlob Dense(const DnnBlob& x, const std::string& weight_key, const std::string& bias_key);
  // Transposed convolution, weights in x out x k x k (PyTorch layout), stride k, no padding, no bias.
  DnnBlob Deconv(const DnnBlob& x, const std::string& weight_key, int stride);
  // Batch norm as a per-channel scale and shift.
  DnnBlob BatchNorm(const DnnBlob& x, const std::string& prefix, double eps);
  // PReLU with one slope per channel (`slope_key`, shape C).
  DnnBlob PRelu(const DnnBlob& x, const std::string& slope_key);
  DnnBlob Sigmoid(const DnnBlob& x);

  DnnBlob Add(const DnnBlob& a, const DnnBlob& b);
  DnnBlob Concat(const std::vector<DnnBlob>& parts);
  // x * gate, with gate N x C x 1 x 1 (a channel attention).
  DnnBlob ScaleChannels(const DnnBlob& x, const DnnBlob& gate);
  // Channel shuffle (ShuffleNet): C = groups x (C / groups) channels read out transposed.
  DnnBlob ShuffleChannels(const DnnBlob& x, int groups);

  // Average pooling, counting zero padding (PyTorch's count_include_pad), output size rounded down.
  DnnBlob AvgPool(const DnnBlob& x, int kernel, int stride, int pad);
  DnnBlob GlobalAvgPool(const DnnBlob& x);
  // Bilinear resizing (dnn_custom_layers.h) to the size of `like`, or by `scale` with a minimum size.
  DnnBlob Bilinear(const DnnBlob& x, const DnnBlob& like, bool align_corners);
  DnnBlob Bilinear(const DnnBlob& x, double scale, int min_size, bool align_corners);
  DnnBlob AdaptiveAvgPool(const DnnBlob& x, const DnnBlob& like);
  DnnBlob AdaptiveAvgPool(const DnnBlob& x, double scale, int min_size);
  // SINet's information blocking: a * (1 - max softmax(b)) + b.
  DnnBlob InformationBlocking(const DnnBlob& a, const DnnBlob& b);

  // The network (its only input named "image"); the builder must not be used afterwards.
  cv::dnn::Net Finish();

  // A tensor as a float Mat of the given shape (checked against the state dict).
  cv::Mat Weights(const std::string& key, const std::vector<std::int64_t>& shape) const;
  // Throws InputError naming the weights file.
  [[noreturn]] void Fail(const std::string& message) const;
  bool Contains(const std::string& key) const { return weights_.Contains(key); }
  // A tensor's shape (throws InputError when missing).
  std::vector<std::int64_t> Shape(const std::string& key) const;

 private:
  DnnBlob AddLayer(const std::string& type, cv::dnn::LayerParams& params, const std::vector<DnnBlob>& inputs,
                   int channels, const std::string& name_hint);
  // Per-channel scale and shift of a batch norm.
  void BatchNormFactors(const std::string& prefix, int channels, double eps, std::vector<float>* scale,
                        std::vector<float>* shift) const;

  const TorchStateDict& weights_;
  int input_channels_;
  cv::dnn::Net net_;
  int counter_ = 0;
};

}  // namespace semslam
