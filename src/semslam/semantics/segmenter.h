#pragma once
// Segmenters turn an image into a Segmentation. Backends:
//   - DnnSegmenter (dnn_segmenter.h): a CNN through OpenCV's dnn module (Torch7 .net such as ENet, ONNX
//     exports, PyTorch state dicts of ESPNetv2 and SINet), described by a model card (model_card.h);
//   - LabelImageSegmenter (label_image_segmenter.h): label or probability images on disk from any external
//   network;
//   - TruthNoisySegmenter (label_image_segmenter.h): ground-truth labels through a noise model, for
//   experiments.
// MakeSegmenter builds one from a spec string (`semslam run --segmenter SPEC`).

#include <cstdint>
#include <filesystem>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <string>
#include <string_view>

#include "semslam/semantics/segmentation.h"

namespace semslam {

class Segmenter {
 public:
  virtual ~Segmenter() = default;

  // One line saying what this is (backend, model, options), for logs and run.json.
  virtual std::string Describe() const = 0;
  // Whether Segment() needs the image (disk-backed segmenters only need the frame index and the image size).
  virtual bool NeedsImage() const { return true; }
  // Whether Segment() needs the frame index.
  virtual bool NeedsFrameIndex() const { return false; }
  // Segments `image` (8-bit grey, BGR or BGRA). `frame_index` names the frame for segmenters that read
  // per-frame files. The result's input size is the image's (or, with no image, the file's). Not thread-safe:
  // one call at a time. Throws InputError for bad or missing input files, InvalidArgument for a bad call.
  virtual Segmentation Segment(const cv::Mat& image, std::int64_t frame_index = -1) = 0;
};

// What a spec may refer to besides itself.
struct SegmenterContext {
  // The sequence's ground-truth label folder (the synthetic city's label_0/), for truth-noisy.
  std::optional<std::filesystem::path> truth_label_dir;
  // Seed for noisy segmenters (mixed with the frame index, so every frame is deterministic).
  std::uint64_t seed = 0;
  // Whether the segmenter will see colour images (a colour camera); `auto` picks its network by this.
  bool colour_images = false;
};

// The folder `auto` reads the weights from when its spec names none:
// $SEMSLAM_SHARED_DATA/segmentation_weights, else ../shared/data/segmentation_weights (the checkout's
// sibling, from the repository root), else the same beside the checkout of a build-tree binary
// (CHECKOUT/build/PRESET/bin/semslam) run from elsewhere.
std::filesystem::path DefaultSegmentationWeightsDir();

// Builds a segmenter from a spec:
//   none                     -> nullptr (no segmentation)
//   enet:FILE                -> the ENet Cityscapes Torch7 model at FILE (EnetCityscapesCard)
//   espnetv2:FILE.pth        -> ESPNetv2 s=2.0 with its Cityscapes state dict (EspNetV2CityscapesCard)
//   sinet:FILE.pth           -> SINet with its Cityscapes state dict (SiNetCityscapesCard)
//   onnx:CARD.yaml           -> any OpenCV dnn model described by a model card (also: card:CARD.yaml)
//   labels:DIR               -> per-frame label images DIR/%06d.png (trainIds) or probabilities DIR/%06d.npy
//   truth-noisy:RATE         -> context.truth_label_dir through the noise model (RATE in [0, 0.9])
//   auto[:DIR]               -> the Cityscapes network for the camera: SINet for colour images (fast enough
//                               for every keyframe, good on colour), ESPNetv2 768 wide (unless width= says
//                               otherwise) for grey ones (SINet reads grey trees as persons); their state
//                               dicts in DIR (default DefaultSegmentationWeightsDir())
// followed by optional ",key=value" settings: alpha=A (confusion model, labels and truth-noisy; default 0.8
// for labels, 1 - RATE for truth-noisy), ids=train|label (labels: trainIds or Cityscapes labelIds), seed=N,
// blobs=F (truth-noisy: share of the errors in blobs, default 0.5), blob_size=PX, threads=N (dnn: OpenCV
// threads, process-wide), resize=stretch|tile (dnn with a fixed input size, see model_card.h), width=N
// (espnetv2, sinet: the network input width; images are scaled to it, aspect ratio kept). Throws
// InvalidArgument naming the problem for a bad spec, InputError for a missing or bad file.
std::unique_ptr<Segmenter> MakeSegmenter(std::string_view spec, const SegmenterContext& context = {});

}  // namespace semslam
