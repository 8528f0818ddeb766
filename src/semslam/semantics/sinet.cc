// SINet for Cityscapes (19 classes), from the paper and the names and shapes of its published state dict.
//
// Encoder (channels 16, 19, 24 | 60, 60 | 84 | 108 at 1/2, 1/4, 1/8, 1/16 of the input):
//   level1      3x3 convolution, stride 2, batch norm, PReLU
//   level2_0,   squeeze-and-excitation separable convolutions with stride 2: depthwise 3x3, a channel
//   level3_0    scaling from dense layers with PReLU on the global average, 1x1 convolution, BN, PReLU
//   level3.i    3 spatial squeeze modules, then BR3 over [level3_0, level3]
//   level4_0    SE separable convolution with stride 2 (dense layers halve the channels first)
//   level4.i    10 spatial squeeze modules, then BR4 over [level4_0, level4], and a 1x1 classifier
// A spatial squeeze module reduces with a grouped 1x1 convolution (2 groups), shuffles the channels, and runs
// two branches on the result whose outputs are concatenated: a branch is either a depthwise 3x3 convolution
// + BN, or a k x 1 and a 1 x k depthwise convolution (each + BN) added, optionally on an n x n average-pooled
// map that is upsampled back after the branch's PReLU and 1x1 convolution; each branch ends with BN. The
// module adds its input when the channel counts allow, then BN + PReLU.
// Decoder (information blocking): the encoder's 1/16 scores upsampled to 1/8 (BN) are confident where their
// softmax peaks; the 1/8 features (level3 through a 1x1 CBR) are let through only where they are not
// (a * (1 - max p) + b), upsampled to 1/4 (BN), the same again with level2_0's output, and a 2x2 transposed
// convolution gives the scores at 1/2.

#include "semslam/semantics/dnn_graph.h"
#include "semslam/semantics/torch_networks.h"

namespace semslam {
namespace {

constexpr double kEps = 1e-3;  // every batch norm of SINet

// Per module: the (kernel, pooling) of its two branches. Pooling 0: a plain 3x3 depthwise convolution;
// 1: the k x 1 + 1 x k pair at full resolution; n > 1: the pair on an n x n average-pooled map.
struct Branch {
  int kernel, pool;
};
constexpr Branch kModules[13][2] = {
    {{3, 1}, {5, 1}}, {{3, 0}, {3, 1}}, {{3, 0}, {3, 1}},                                      // level3
    {{3, 1}, {5, 1}}, {{3, 0}, {3, 1}}, {{5, 1}, {5, 4}}, {{3, 2}, {5, 8}}, {{3, 1}, {5, 1}},  // level4.0-4
    {{3, 1}, {5, 1}}, {{3, 0}, {3, 1}}, {{5, 1}, {5, 8}}, {{3, 2}, {5, 4}}, {{3, 0}, {5, 2}},  // level4.5-9
};

class SiNetBuilder {
 public:
  explicit SiNetBuilder(const TorchStateDict& weights) : g_(weights, 3) {}

  cv::dnn::Net Build() {
    const std::string e = "encoder.";
    const DnnBlob image = g_.input();
    const DnnBlob l1 =
        g_.PRelu(g_.Conv(image, e + "level1.conv.weight", {2, 1, 1, 1, 1}, "", e + "level1.bn", kEps),
                 e + "level1.act.weight");
    const DnnBlob l2 = SeSeparable(e + "level2_0", l1);
    const DnnBlob l3_0 = SeSeparable(e + "level3_0", l2);
    DnnBlob l3 = l3_0;
    for (int i = 0; i < 3; ++i) l3 = Module(e + "level3." + std::to_string(i), l3, kModules[i], i > 0);
    const DnnBlob l4_0 = SeSeparable(e + "level4_0", Br(g_.Concat({l3_0, l3}), e + "BR3"));
    DnnBlob l4 = l4_0;
    for (int i = 0; i < 10; ++i)
      l4 = Module(e + "level4." + std::to_string(i), l4, kModules[3 + i], i != 0 && i != 5);
    const DnnBlob coarse = g_.Conv(Br(g_.Concat({l4_0, l4}), e + "BR4"), e + "classifier.conv.weight", {});

    const DnnBlob stage1 = g_.BatchNorm(g_.Bilinear(coarse, 2.0, 1, false), "bn_4", kEps);
    const DnnBlob side =
        g_.PRelu(g_.Conv(l3, "level3_C.conv.weight", {}, "", "level3_C.bn", kEps), "level3_C.act.weight");
    const DnnBlob stage2 =
        g_.BatchNorm(g_.Bilinear(g_.InformationBlocking(side, stage1), 2.0, 1, false), "bn_3", kEps);
    const DnnBlob stage3 = g_.InformationBlocking(l2, stage2);
    g_.Deconv(stage3, "classifier.weight", 2);
    return g_.Finish();
  }

 private:
  DnnBlob Br(const DnnBlob& x, const std::string& p) {
    return g_.PRelu(g_.BatchNorm(x, p + ".bn", kEps), p + ".act.weight");
  }

  DnnBlob SeSeparable(const std::string& p, const DnnBlob& x) {
    const DnnBlob depthwise = g_.Conv(x, p + ".conv.0.weight", {2, 1, 1, 1, x.channels});
    // Squeeze: dense layers (each followed by PReLU) on the global average give each channel its factor.
    DnnBlob squeeze = g_.GlobalAvgPool(depthwise);
    for (int i = 0; g_.Contains(p + ".conv.1.dense." + std::to_string(i) + ".weight"); i += 2) {
      const std::string dense = p + ".conv.1.dense." + std::to_string(i);
      squeeze = g_.Dense(squeeze, dense + ".weight", dense + ".bias");
      squeeze = g_.PRelu(squeeze, p + ".conv.1.dense." + std::to_string(i + 1) + ".weight");
    }
    const DnnBlob excited = g_.ScaleChannels(depthwise, squeeze);
    const DnnBlob out = g_.Conv(excited, p + ".conv.2.weight", {}, "", p + ".bn", kEps);
    return g_.PRelu(out, p + ".act.weight");
  }

  DnnBlob BranchOf(const std::string& p, const DnnBlob& x, const Branch& branch) {
    DnnBlob y;
    if (branch.pool == 0) {
      y = g_.Conv(x, p + ".conv.0.weight", {1, 1, 1, 1, x.channels}, "", p + ".conv.1", kEps);
    } else {
      const DnnBlob in = branch.pool > 1 ? g_.AvgPool(x, branch.pool, branch.pool, 0) : x;
      const int r = branch.kernel / 2;
      const DnnBlob v = g_.Conv(in, p + ".vertical.weight", {1, r, 0, 1, x.channels}, "", p + ".B_v", kEps);
      const DnnBlob h = g_.Conv(in, p + ".horizontal.weight", {1, 0, r, 1, x.channels}, "", p + ".B_h", kEps);
      y = g_.Add(v, h);
    }
    // PReLU, 1x1 convolution and the final BN (folded in: a bilinear upsampling commutes with a per-channel
    // affine map, its weights summing to 1).
    y = g_.Conv(g_.PRelu(y, p + ".act_conv1x1.0.weight"), p + ".act_conv1x1.1.weight", {}, "", p + ".bn",
                kEps);
    if (branch.pool > 1) y = g_.Bilinear(y, branch.pool, 1, true);
    return y;
  }

  DnnBlob Module(const std::string& p, const DnnBlob& x, const Branch (&branches)[2], bool residual) {
    const DnnBlob reduced = g_.ShuffleChannels(g_.Conv(x, p + ".c1.conv.weight", {1, 0, 0, 1, 2}), 2);
    DnnBlob out =
        g_.Concat({BranchOf(p + ".d1", reduced, branches[0]), BranchOf(p + ".d2", reduced, branches[1])});
    if (residual) {
      if (out.channels != x.channels)
        g_.Fail("SINet: module " + p + " changes the channel count: not the expected network");
      out = g_.Add(out, x);
    }
    return Br(out, p + ".BR");
  }

  DnnGraph g_;
};

}  // namespace

cv::dnn::Net BuildSiNet(const TorchStateDict& weights) { return SiNetBuilder(weights).Build(); }

}  // namespace semslam
