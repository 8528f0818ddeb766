#pragma once
// A CNN through OpenCV's dnn module (CPU), described by a model card: Torch7 .net files (ENet), ONNX exports
// (PSPNet, BiSeNet, DDRNet, ...) and PyTorch state dicts of the networks semslam builds itself
// (torch_networks.h: ESPNetv2, SINet). Keeps the network's output resolution and maps it back to the input
// image. Input images may be 8-bit grey (fed as three equal channels), BGR or BGRA.

#include <memory>
#include <string>
#include <vector>

#include "semslam/semantics/model_card.h"
#include "semslam/semantics/segmenter.h"

namespace semslam {

struct DnnSegmenterOptions {
  // OpenCV threads (cv::setNumThreads, process-wide) set before each forward pass; 0 leaves them alone.
  int threads = 0;
  void Check() const;
};

class DnnSegmenter : public Segmenter {
 public:
  using Options = DnnSegmenterOptions;

  // Loads the network. Throws InputError naming the file when it is missing or OpenCV cannot read it.
  explicit DnnSegmenter(ModelCard card, Options options = {});
  ~DnnSegmenter() override;

  std::string Describe() const override;
  Segmentation Segment(const cv::Mat& image, std::int64_t frame_index = -1) override;

  const ModelCard& card() const { return card_; }
  // The network input size used for an image of `image_size` (see ModelCard: fixed, the image's rounded to
  // the divisor, or scaled to the card's width with the aspect ratio kept).
  cv::Size NetworkInputSize(cv::Size image_size) const;
  // The preprocessed NCHW float blob for an image (exposed for tests).
  cv::Mat Preprocess(const cv::Mat& image) const;

 private:
  // Runs the network on one image (resized to the network's input as the card says); the raw output.
  cv::Mat Forward(const cv::Mat& image);
  // One CV_32F plane per output channel (views into `output` for NCHW).
  std::vector<cv::Mat> ScorePlanes(cv::Mat& output) const;
  // The planes of the channels that are not dropped (ModelCard kDropChannel).
  std::vector<cv::Mat> KeptPlanes(cv::Mat& output) const;

  ModelCard card_;
  Options options_;
  struct Network;  // the cv::dnn::Net, kept out of this header
  std::unique_ptr<Network> network_;
};

}  // namespace semslam
