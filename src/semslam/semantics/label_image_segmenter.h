#pragma once
// Segmenters that read per-frame files instead of running a network:
//   - LabelImageSegmenter: label or probability images written by any external network, named like the frames
//     (DIR/%06d.png, or %010d.png as in KITTI raw): 8-bit Cityscapes trainIds (255 = none) or labelIds
//     (mapped to trainIds), optionally with DIR/%06d_conf.png (8-bit probability of the label times 255); or
//     probabilities DIR/%06d.npy (NumPy, H x W x C or C x H x W, float32 or uint8 = p * 255, C = 19 trainIds,
//     or 20 with an 'unlabeled' channel first). Label-only input gets the confusion model (alpha for the
//     given class).
//   - TruthNoisySegmenter: ground-truth trainId images (the synthetic city's label_0/) through AddLabelNoise.

#include <cstdint>
#include <filesystem>
#include <opencv2/core/mat.hpp>
#include <string>

#include "semslam/semantics/segmenter.h"

namespace semslam {

// The file of `frame_index` in `dir` with `extension` (".png"): %06d, else %010d when only that exists;
// nullopt-like empty path when neither does.
std::filesystem::path FindFrameFile(const std::filesystem::path& dir, std::int64_t frame_index,
                                    const std::string& extension, const std::string& suffix = "");

// Reads an 8-bit single-channel label image (grey PNG; a colour image is an error). Throws InputError.
cv::Mat ReadLabelImage(const std::filesystem::path& path);
// Maps Cityscapes labelIds to trainIds (255 stays 255).
cv::Mat LabelIdsToTrainIds(const cv::Mat& label_ids);

// A NumPy .npy array of probabilities: H x W x C or C x H x W (C = 19 or 20), '<f4' or '|u1'. Returns one
// CV_32F plane per channel (uint8 scaled by 1/255). Throws InputError naming the file.
std::vector<cv::Mat> ReadNpyProbabilities(const std::filesystem::path& path);

class LabelImageSegmenter : public Segmenter {
 public:
  struct Options {
    float alpha = 0.8f;      // confusion model for label-only files
    bool label_ids = false;  // the PNGs hold Cityscapes labelIds, not trainIds
    void Check() const;
  };
  // Throws InputError when `dir` is not a folder.
  LabelImageSegmenter(std::filesystem::path dir, Options options);

  std::string Describe() const override;
  bool NeedsImage() const override { return false; }
  bool NeedsFrameIndex() const override { return true; }
  // Reads the frame's file; `image` (may be empty) only gives the input size the result refers to (the file
  // is stretched over it when the sizes differ). Throws InputError when the file is missing or bad.
  Segmentation Segment(const cv::Mat& image, std::int64_t frame_index) override;

 private:
  std::filesystem::path dir_;
  Options options_;
};

struct LabelNoiseOptions {
  double rate = 0.25;          // probability that a labeled pixel comes out wrong
  double blob_fraction = 0.5;  // share of the wrong pixels that lie in spatially correlated blobs
  double blob_size = 0.0;      // correlation length of the blobs in pixels; 0 = image height / 8
  void Check() const;
};

// Each labeled pixel of `truth` (CV_8U trainIds; 255 and other non-classes stay as they are) is wrong with
// probability `rate`: a `blob_fraction` share of the errors in smooth random blobs (one wrong class per
// blob), the rest as independent salt noise (a uniformly random other class). Deterministic for a given seed.
cv::Mat AddLabelNoise(const cv::Mat& truth, const LabelNoiseOptions& options, std::uint64_t seed);

class TruthNoisySegmenter : public Segmenter {
 public:
  struct Options {
    LabelNoiseOptions noise;
    float alpha = -1.0f;     // confusion model; < 0: 1 - rate (at least 1/19)
    std::uint64_t seed = 0;  // mixed with the frame index
    void Check() const;
    float ResolvedAlpha() const;
  };
  // `truth_dir` holds %06d.png trainId images. Throws InputError when it is not a folder.
  TruthNoisySegmenter(std::filesystem::path truth_dir, Options options);

  std::string Describe() const override;
  bool NeedsImage() const override { return false; }
  bool NeedsFrameIndex() const override { return true; }
  Segmentation Segment(const cv::Mat& image, std::int64_t frame_index) override;
  // The noisy labels of a frame (what Segment() observes), at the label image's size.
  cv::Mat NoisyLabels(std::int64_t frame_index) const;

 private:
  std::filesystem::path truth_dir_;
  Options options_;
};

}  // namespace semslam
