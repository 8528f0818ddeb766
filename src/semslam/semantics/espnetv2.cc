// ESPNetv2 (s = 2.0) for Cityscapes, from the paper and the names and shapes of its published state dict.
//
// Encoder (channels 32, 128, 256, 512 at 1/2, 1/4, 1/8, 1/16 of the input):
//   level1     3x3 convolution, stride 2, batch norm, PReLU
//   levelN_0   strided EESP unit: [3x3 average pooling of the input | EESP with stride 2], concatenated, plus
//              the input image average-pooled down to this size and projected (3x3 CBR, 1x1 CB): "input
//              reinforcement"; then PReLU
//   levelN.i   EESP units with a residual connection
// An EESP unit reduces with a grouped 1x1 convolution (4 groups), runs 4 depthwise 3x3 convolutions with
// growing dilation and adds each to the previous one (hierarchical feature fusion, against gridding), then
// concatenates them, normalizes, and expands with a grouped 1x1 convolution.
// Decoder: from 1/16 up, efficient pyramid pooling (a projection to 10 channels, then at scales 2, 1.5, 1,
// 0.5, 0.1 a depthwise 3x3 convolution between a resizing and its inverse; merged by batch norm, channel
// shuffle and a grouped 3x3 convolution), upsampled x2 and added to the encoder's features at that level,
// which pass through a channel gate (global pooling, 1x1 convolution, sigmoid) times a grouped 3x3
// convolution.

#include "semslam/semantics/dnn_graph.h"
#include "semslam/semantics/torch_networks.h"

namespace semslam {
namespace {

constexpr double kEps = 1e-5;  // PyTorch's batch norm default

class EspNetV2Builder {
 public:
  explicit EspNetV2Builder(const TorchStateDict& weights) : g_(weights, 3) {}

  cv::dnn::Net Build() {
    const DnnBlob image = g_.input();
    // Input reinforcement: the image average-pooled to every level's size.
    std::vector<DnnBlob> pooled_image = {image};
    for (int i = 0; i < 4; ++i) pooled_image.push_back(g_.AvgPool(pooled_image.back(), 3, 2, 1));

    const std::string b = "base_net.";
    const DnnBlob l1 = Cbr(image, b + "level1", 2, 1);
    const DnnBlob l2 = DownSampler(b + "level2_0", l1, pooled_image[2], {1, 2, 3, 4});
    DnnBlob l3 = DownSampler(b + "level3_0", l2, pooled_image[3], {1, 2, 3, 4});
    for (int i = 0; i < 3; ++i) l3 = Eesp(b + "level3." + std::to_string(i), l3, 1, {1, 2, 3, 4}, false);
    DnnBlob l4 = DownSampler(b + "level4_0", l3, pooled_image[4], {1, 2, 3, 4});
    // Receptive field limit 7 at this level: kernels 3, 5, 7, 9 become 3, 3, 5, 7 (dilations 1, 1, 2, 3).
    for (int i = 0; i < 7; ++i) l4 = Eesp(b + "level4." + std::to_string(i), l4, 1, {1, 1, 2, 3}, false);

    DnnBlob d = PyramidPool("bu_dec_l1", l4, false);
    d = Merge(d, EfficientPointwise("merge_enc_dec_l2", l3), "bu_br_l2");
    d = PyramidPool("bu_dec_l2", d, false);
    d = Merge(d, EfficientPointwise("merge_enc_dec_l3", l2), "bu_br_l3");
    d = PyramidPool("bu_dec_l3", d, false);
    d = Merge(d, EfficientPointwise("merge_enc_dec_l4", l1), "bu_br_l4");
    d = PyramidPool("bu_dec_l4", d, true);
    g_.Bilinear(d, image, true);
    return g_.Finish();
  }

 private:
  // Convolution (padding keeps the size) + batch norm + PReLU, with espnet's names: P.conv, P.bn, P.act.
  DnnBlob Cbr(const DnnBlob& x, const std::string& p, int stride, int groups, int dilation = 1) {
    const int k = static_cast<int>(g_.Shape(p + ".conv.weight")[2]);
    const int pad = k / 2 * dilation;
    const DnnBlob c =
        g_.Conv(x, p + ".conv.weight", {stride, pad, pad, dilation, groups}, "", p + ".bn", kEps);
    return g_.PRelu(c, p + ".act.weight");
  }
  DnnBlob Cb(const DnnBlob& x, const std::string& p, int groups) {
    return g_.Conv(x, p + ".conv.weight", {1, 0, 0, 1, groups}, "", p + ".bn", kEps);
  }
  DnnBlob Br(const DnnBlob& x, const std::string& bn, const std::string& act) {
    return g_.PRelu(g_.BatchNorm(x, bn, kEps), act);
  }
  // The decoder's CBR: P.cbr.0 convolution, P.cbr.1 batch norm, P.cbr.2 PReLU.
  DnnBlob CbrSequence(const DnnBlob& x, const std::string& p, int groups) {
    const int k = static_cast<int>(g_.Shape(p + ".cbr.0.weight")[2]);
    const DnnBlob c = g_.Conv(x, p + ".cbr.0.weight", {1, k / 2, k / 2, 1, groups}, "", p + ".cbr.1", kEps);
    return g_.PRelu(c, p + ".cbr.2.weight");
  }

  DnnBlob Eesp(const std::string& p, const DnnBlob& x, int stride, const std::vector<int>& dilations,
               bool downsample) {
    const int branches = static_cast<int>(dilations.size());
    const DnnBlob reduced = Cbr(x, p + ".proj_1x1", 1, branches);
    std::vector<DnnBlob> fused;
    for (int i = 0; i < branches; ++i) {
      const int d = dilations[static_cast<size_t>(i)];
      const DnnBlob branch = g_.Conv(reduced, p + ".spp_dw." + std::to_string(i) + ".conv.weight",
                                     {stride, d, d, d, reduced.channels});
      fused.push_back(fused.empty() ? branch : g_.Add(branch, fused.back()));  // hierarchical fusion
    }
    const DnnBlob merged = Br(g_.Concat(fused), p + ".br_after_cat.bn", p + ".br_after_cat.act.weight");
    const DnnBlob expanded = Cb(merged, p + ".conv_1x1_exp", branches);
    if (downsample) return expanded;
    if (expanded.channels != x.channels) {
      g_.Fail("ESPNetv2: unit " + p + " changes the channel count: not the expected network");
    }
    return g_.PRelu(g_.Add(expanded, x), p + ".module_act.weight");
  }

  DnnBlob DownSampler(const std::string& p, const DnnBlob& x, const DnnBlob& image,
                      const std::vector<int>& dilations) {
    const DnnBlob avg = g_.AvgPool(x, 3, 2, 1);
    const DnnBlob eesp = Eesp(p + ".eesp", x, 2, dilations, true);
    const DnnBlob cat = g_.Concat({avg, eesp});
    const DnnBlob reinforced = Cb(Cbr(image, p + ".inp_reinf.0", 1, 1), p + ".inp_reinf.1", 1);
    return g_.PRelu(g_.Add(cat, reinforced), p + ".act.weight");
  }

  DnnBlob PyramidPool(const std::string& p, const DnnBlob& x, bool last) {
    const DnnBlob projected = CbrSequence(x, p + ".projection_layer", 1);
    const double scales[] = {2.0, 1.5, 1.0, 0.5, 0.1};
    constexpr int kMinSize = 5;
    std::vector<DnnBlob> levels;
    for (int i = 0; i < 5; ++i) {
      const std::string stage = p + ".stages." + std::to_string(i) + ".weight";
      const auto depthwise = [&](const DnnBlob& t) { return g_.Conv(t, stage, {1, 1, 1, 1, t.channels}); };
      const double s = scales[i];
      if (s > 1.0) {
        levels.push_back(g_.AdaptiveAvgPool(depthwise(g_.Bilinear(projected, s, kMinSize, true)), projected));
      } else if (s < 1.0) {
        levels.push_back(g_.Bilinear(depthwise(g_.AdaptiveAvgPool(projected, s, kMinSize)), projected, true));
      } else {
        levels.push_back(depthwise(projected));
      }
    }
    DnnBlob merged = Br(g_.Concat(levels), p + ".merge_layer.0.br.0", p + ".merge_layer.0.br.1.weight");
    merged = g_.ShuffleChannels(merged, 5);
    merged = CbrSequence(merged, p + ".merge_layer.2", projected.channels);
    const DnnBlob out =
        g_.Conv(merged, p + ".merge_layer.3.weight", {}, last ? p + ".merge_layer.3.bias" : "");
    if (last) return out;
    return Br(out, p + ".br.br.0", p + ".br.br.1.weight");
  }

  // Encoder features gated per channel: (grouped 3x3 CBR) * sigmoid(1x1 conv of their global average).
  DnnBlob EfficientPointwise(const std::string& p, const DnnBlob& x) {
    const DnnBlob gate = g_.Sigmoid(g_.Conv(g_.GlobalAvgPool(x), p + ".wt_layer.1.weight", {}));
    const std::vector<std::int64_t> shape = g_.Shape(p + ".expansion_layer.cbr.0.weight");
    if (shape.size() != 4 || shape[1] <= 0 || x.channels % shape[1] != 0) {
      g_.Weights(p + ".expansion_layer.cbr.0.weight", {gate.channels, x.channels, 3, 3});  // throws
    }
    const int groups = x.channels / static_cast<int>(shape[1]);
    return g_.ScaleChannels(CbrSequence(x, p + ".expansion_layer", groups), gate);
  }

  // Decoder x2 upsampling plus the gated encoder features, then batch norm + PReLU.
  DnnBlob Merge(const DnnBlob& decoder, const DnnBlob& encoder, const std::string& br) {
    const DnnBlob up = g_.Bilinear(decoder, 2.0, 1, true);
    return Br(g_.Add(up, encoder), br + ".0", br + ".1.weight");
  }

  DnnGraph g_;
};

}  // namespace

cv::dnn::Net BuildEspNetV2(const TorchStateDict& weights) { return EspNetV2Builder(weights).Build(); }

}  // namespace semslam
