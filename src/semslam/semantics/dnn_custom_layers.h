#pragma once
// Layers that OpenCV 4.6's dnn module lacks (or does with other conventions), registered with its
// LayerFactory under semslam's own type names, for the networks built in C++ (torch_networks.h). Each takes
// NCHW float blobs:
//   - kBilinearLayer: bilinear resizing with PyTorch's conventions (align_corners true: corners map onto
//     corners; false: half-pixel centres, sources below 0 clamped to 0);
//   - kAdaptiveAvgPoolLayer: PyTorch's adaptive average pooling (output cell i averages input rows
//     floor(i * in / out) .. ceil((i + 1) * in / out) - 1, the same for columns);
//   - kInformationBlockingLayer: SINet's information blocking, out = a * (1 - max_c softmax(b)_c) + b for two
//     inputs a and b of the same shape.
// The two resizing layers take their output size either from a second input (its height and width) or from
// the parameters "scale" and "min_size": out = max(ceil(in * scale), min_size).

namespace semslam {

inline constexpr const char* kBilinearLayer = "SemslamBilinear";
inline constexpr const char* kAdaptiveAvgPoolLayer = "SemslamAdaptiveAvgPool";
inline constexpr const char* kInformationBlockingLayer = "SemslamInformationBlocking";

// Registers the layers (once per process; thread-safe).
void RegisterCustomDnnLayers();

// The output size of the resizing layers for an input of `in` pixels (see above).
int ScaledSize(int in, double scale, int min_size);

}  // namespace semslam
