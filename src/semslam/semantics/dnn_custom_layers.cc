#include "semslam/semantics/dnn_custom_layers.h"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>
#include <opencv2/dnn/layer.details.hpp>
#include <vector>

namespace semslam {
namespace {

using cv::dnn::LayerParams;
using cv::dnn::MatShape;

// Output height and width of a resizing layer: from the second input when there is one, else by scale.
class ResizingLayer : public cv::dnn::Layer {
 public:
  explicit ResizingLayer(const LayerParams& params) : Layer(params) {
    scale_ = params.get<double>("scale", 0.0);
    min_size_ = params.get<int>("min_size", 1);
  }

  bool getMemoryShapes(const std::vector<MatShape>& inputs, int /*required_outputs*/,
                       std::vector<MatShape>& outputs, std::vector<MatShape>& /*internals*/) const override {
    CV_Assert(!inputs.empty() && inputs[0].size() == 4);
    MatShape out = inputs[0];
    if (inputs.size() >= 2) {
      CV_Assert(inputs[1].size() == 4);
      out[2] = inputs[1][2];
      out[3] = inputs[1][3];
    } else {
      CV_Assert(scale_ > 0.0);
      out[2] = ScaledSize(inputs[0][2], scale_, min_size_);
      out[3] = ScaledSize(inputs[0][3], scale_, min_size_);
    }
    outputs.assign(1, out);
    return false;
  }

 protected:
  double scale_ = 0.0;
  int min_size_ = 1;
};

// One output coordinate's two source taps and the weight of the second.
struct Tap {
  int i0, i1;
  float w1;
};

std::vector<Tap> BilinearTaps(int in, int out, bool align_corners) {
  std::vector<Tap> taps(static_cast<size_t>(out));
  for (int i = 0; i < out; ++i) {
    double src;
    if (align_corners) {
      src = out > 1 ? static_cast<double>(i) * (in - 1) / (out - 1) : 0.0;
    } else {
      src = std::max((i + 0.5) * in / out - 0.5, 0.0);
    }
    const int i0 = std::min(static_cast<int>(std::floor(src)), in - 1);
    taps[static_cast<size_t>(i)] = {i0, std::min(i0 + 1, in - 1), static_cast<float>(src - i0)};
  }
  return taps;
}

class BilinearLayer : public ResizingLayer {
 public:
  explicit BilinearLayer(const LayerParams& params) : ResizingLayer(params) {
    align_corners_ = params.get<bool>("align_corners", false);
  }
  static cv::Ptr<cv::dnn::Layer> Create(LayerParams& params) { return cv::makePtr<BilinearLayer>(params); }

  void forward(cv::InputArrayOfArrays inputs_arr, cv::OutputArrayOfArrays outputs_arr,
               cv::OutputArrayOfArrays /*internals*/) override {
    std::vector<cv::Mat> inputs, outputs;
    inputs_arr.getMatVector(inputs);
    outputs_arr.getMatVector(outputs);
    const cv::Mat& in = inputs[0];
    cv::Mat& out = outputs[0];
    const int planes = in.size[0] * in.size[1];
    const int ih = in.size[2], iw = in.size[3], oh = out.size[2], ow = out.size[3];
    const std::vector<Tap> rows = BilinearTaps(ih, oh, align_corners_);
    const std::vector<Tap> cols = BilinearTaps(iw, ow, align_corners_);
    cv::parallel_for_(cv::Range(0, planes), [&](const cv::Range& range) {
      std::vector<float> top(static_cast<size_t>(ow)), bottom(static_cast<size_t>(ow));
      for (int p = range.start; p < range.end; ++p) {
        const float* src = in.ptr<float>() + static_cast<size_t>(p) * ih * iw;
        float* dst = out.ptr<float>() + static_cast<size_t>(p) * oh * ow;
        for (int y = 0; y < oh; ++y) {
          const Tap& r = rows[static_cast<size_t>(y)];
          const float* a = src + static_cast<size_t>(r.i0) * iw;
          const float* b = src + static_cast<size_t>(r.i1) * iw;
          float* d = dst + static_cast<size_t>(y) * ow;
          for (int x = 0; x < ow; ++x) {
            const Tap& c = cols[static_cast<size_t>(x)];
            const float t = a[c.i0] + (a[c.i1] - a[c.i0]) * c.w1;
            const float u = b[c.i0] + (b[c.i1] - b[c.i0]) * c.w1;
            d[x] = t + (u - t) * r.w1;
          }
        }
      }
    });
  }

 private:
  bool align_corners_ = false;
};

class AdaptiveAvgPoolLayer : public ResizingLayer {
 public:
  explicit AdaptiveAvgPoolLayer(const LayerParams& params) : ResizingLayer(params) {}
  static cv::Ptr<cv::dnn::Layer> Create(LayerParams& params) {
    return cv::makePtr<AdaptiveAvgPoolLayer>(params);
  }

  void forward(cv::InputArrayOfArrays inputs_arr, cv::OutputArrayOfArrays outputs_arr,
               cv::OutputArrayOfArrays /*internals*/) override {
    std::vector<cv::Mat> inputs, outputs;
    inputs_arr.getMatVector(inputs);
    outputs_arr.getMatVector(outputs);
    const cv::Mat& in = inputs[0];
    cv::Mat& out = outputs[0];
    const int planes = in.size[0] * in.size[1];
    const int ih = in.size[2], iw = in.size[3], oh = out.size[2], ow = out.size[3];
    const auto bounds = [](int n_in, int n_out) {
      std::vector<std::pair<int, int>> b(static_cast<size_t>(n_out));
      for (int i = 0; i < n_out; ++i) {
        b[static_cast<size_t>(i)] = {static_cast<int>(static_cast<long>(i) * n_in / n_out),
                                     static_cast<int>((static_cast<long>(i + 1) * n_in + n_out - 1) / n_out)};
      }
      return b;
    };
    const auto rows = bounds(ih, oh), cols = bounds(iw, ow);
    cv::parallel_for_(cv::Range(0, planes), [&](const cv::Range& range) {
      std::vector<float> row_sum(static_cast<size_t>(iw));
      for (int p = range.start; p < range.end; ++p) {
        const float* src = in.ptr<float>() + static_cast<size_t>(p) * ih * iw;
        float* dst = out.ptr<float>() + static_cast<size_t>(p) * oh * ow;
        for (int y = 0; y < oh; ++y) {
          const auto [y0, y1] = rows[static_cast<size_t>(y)];
          std::fill(row_sum.begin(), row_sum.end(), 0.0f);
          for (int sy = y0; sy < y1; ++sy) {
            const float* s = src + static_cast<size_t>(sy) * iw;
            for (int x = 0; x < iw; ++x) row_sum[static_cast<size_t>(x)] += s[x];
          }
          for (int x = 0; x < ow; ++x) {
            const auto [x0, x1] = cols[static_cast<size_t>(x)];
            float sum = 0.0f;
            for (int sx = x0; sx < x1; ++sx) sum += row_sum[static_cast<size_t>(sx)];
            dst[static_cast<size_t>(y) * ow + x] = sum / static_cast<float>((y1 - y0) * (x1 - x0));
          }
        }
      }
    });
  }
};

class InformationBlockingLayer : public cv::dnn::Layer {
 public:
  explicit InformationBlockingLayer(const LayerParams& params) : Layer(params) {}
  static cv::Ptr<cv::dnn::Layer> Create(LayerParams& params) {
    return cv::makePtr<InformationBlockingLayer>(params);
  }

  bool getMemoryShapes(const std::vector<MatShape>& inputs, int /*required_outputs*/,
                       std::vector<MatShape>& outputs, std::vector<MatShape>& /*internals*/) const override {
    CV_Assert(inputs.size() == 2 && inputs[0].size() == 4 && inputs[0] == inputs[1]);
    outputs.assign(1, inputs[0]);
    return false;
  }

  void forward(cv::InputArrayOfArrays inputs_arr, cv::OutputArrayOfArrays outputs_arr,
               cv::OutputArrayOfArrays /*internals*/) override {
    std::vector<cv::Mat> inputs, outputs;
    inputs_arr.getMatVector(inputs);
    outputs_arr.getMatVector(outputs);
    const cv::Mat& a = inputs[0];
    const cv::Mat& b = inputs[1];
    cv::Mat& out = outputs[0];
    const int n = a.size[0], channels = a.size[1];
    const size_t plane = static_cast<size_t>(a.size[2]) * a.size[3];
    for (int i = 0; i < n; ++i) {
      const size_t base = static_cast<size_t>(i) * channels * plane;
      const float* pa = a.ptr<float>() + base;
      const float* pb = b.ptr<float>() + base;
      float* po = out.ptr<float>() + base;
      cv::parallel_for_(cv::Range(0, static_cast<int>(plane)), [&](const cv::Range& range) {
        for (int k = range.start; k < range.end; ++k) {
          float best = pb[k];
          for (int c = 1; c < channels; ++c) best = std::max(best, pb[static_cast<size_t>(c) * plane + k]);
          float sum = 0.0f;
          for (int c = 0; c < channels; ++c) sum += std::exp(pb[static_cast<size_t>(c) * plane + k] - best);
          const float keep = 1.0f - 1.0f / sum;  // 1 - the largest class probability
          for (int c = 0; c < channels; ++c) {
            const size_t at = static_cast<size_t>(c) * plane + k;
            po[at] = pa[at] * keep + pb[at];
          }
        }
      });
    }
  }
};

}  // namespace

int ScaledSize(int in, double scale, int min_size) {
  return std::max(static_cast<int>(std::ceil(in * scale)), min_size);
}

void RegisterCustomDnnLayers() {
  static std::once_flag once;
  std::call_once(once, [] {
    cv::dnn::LayerFactory::registerLayer(kBilinearLayer, BilinearLayer::Create);
    cv::dnn::LayerFactory::registerLayer(kAdaptiveAvgPoolLayer, AdaptiveAvgPoolLayer::Create);
    cv::dnn::LayerFactory::registerLayer(kInformationBlockingLayer, InformationBlockingLayer::Create);
  });
}

}  // namespace semslam
