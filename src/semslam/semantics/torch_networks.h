#pragma once
// Segmentation networks written in C++ from their papers, with the layer names and shapes of their published
// PyTorch state dicts, built as OpenCV dnn networks (dnn_graph.h) and fed with those weights:
//  - ESPNetv2 (Mehta, Rastegari, Shapiro, Hajishirzi, CVPR 2019), width s = 2.0, Cityscapes head: strided
//    EESP units with input reinforcement, an encoder of 4 + 3 + 7 units, and a decoder of efficient pyramid
//    pooling blocks merged with the encoder through channel-gated group convolutions. Input RGB with ImageNet
//    statistics, height and width multiples of 16; output 20 logits at the input size (trainIds 0-18, then
//    background).
//  - SINet (Park, Sjösdal, Yoo, Kwak 2019), the Cityscapes variant: squeeze-and-excitation separable
//    convolutions, spatial squeeze modules (two branches of k x 1 + 1 x k depthwise convolutions, some on an
//    average-pooled map), and the information blocking decoder. Input as ESPNetv2, height and width
//    multiples of 128; output 19 logits at half the input size.
// Both throw InputError naming the file and tensor when the state dict is not the expected network's.

#include <opencv2/dnn.hpp>
#include <string>
#include <vector>

#include "semslam/semantics/torch_state_dict.h"

namespace semslam {

cv::dnn::Net BuildEspNetV2(const TorchStateDict& weights);
cv::dnn::Net BuildSiNet(const TorchStateDict& weights);

struct TorchArchitecture {
  std::string name;   // "espnetv2", "sinet"
  int size_divisor;   // input height and width must be multiples of this
  int output_stride;  // input size / output size
  cv::dnn::Net (*build)(const TorchStateDict&);
};
// The architectures semslam can build; nullptr for an unknown name.
const TorchArchitecture* FindTorchArchitecture(const std::string& name);
std::vector<std::string> TorchArchitectureNames();

}  // namespace semslam
