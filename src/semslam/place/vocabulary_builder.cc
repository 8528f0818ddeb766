#include "semslam/place/vocabulary_builder.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <set>

#include "semslam/core/error.h"
#include "semslam/features/orb_pattern.h"

namespace semslam {
namespace {

bool IsImageFile(const std::filesystem::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  static const std::set<std::string> kExtensions = {".png", ".jpg", ".jpeg", ".pgm",
                                                    ".ppm", ".bmp", ".tif",  ".tiff"};
  return kExtensions.count(ext) > 0;
}

std::vector<std::filesystem::path> ImagesIn(const std::filesystem::path& folder) {
  std::vector<std::filesystem::path> images;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(folder, ec)) {
    if (entry.is_regular_file() && IsImageFile(entry.path())) images.push_back(entry.path());
  }
  std::sort(images.begin(), images.end());
  return images;
}

}  // namespace

std::vector<std::filesystem::path> ListTrainingImages(const std::vector<std::filesystem::path>& folders,
                                                      size_t max_images) {
  if (folders.empty()) throw InvalidArgument("vocabulary: no image folders given");
  std::vector<std::filesystem::path> all;
  for (const auto& folder : folders) {
    if (!std::filesystem::is_directory(folder)) throw InputError(folder, "not a folder");
    std::vector<std::filesystem::path> images = ImagesIn(folder);
    if (images.empty()) {
      // A KITTI-layout dataset: its left images.
      std::vector<std::filesystem::path> subfolders;
      if (std::filesystem::is_directory(folder / "image_0")) subfolders.push_back(folder / "image_0");
      std::error_code ec;
      if (std::filesystem::is_directory(folder / "sequences")) {
        for (const auto& entry : std::filesystem::directory_iterator(folder / "sequences", ec)) {
          if (std::filesystem::is_directory(entry.path() / "image_0"))
            subfolders.push_back(entry.path() / "image_0");
        }
      }
      std::sort(subfolders.begin(), subfolders.end());
      for (const auto& sub : subfolders) {
        const auto more = ImagesIn(sub);
        images.insert(images.end(), more.begin(), more.end());
      }
    }
    if (images.empty())
      throw InputError(folder, "no images in this folder (nor in image_0/ or sequences/*/image_0/)");
    all.insert(all.end(), images.begin(), images.end());
  }
  if (max_images > 0 && all.size() > max_images) {
    std::vector<std::filesystem::path> picked;
    picked.reserve(max_images);
    for (size_t i = 0; i < max_images; ++i) picked.push_back(all[i * all.size() / max_images]);
    all = std::move(picked);
  }
  return all;
}

std::vector<std::vector<Descriptor>> ExtractTrainingDescriptors(
    const std::vector<std::filesystem::path>& images, const OrbOptions& orb,
    const std::function<void(size_t, size_t)>& progress) {
  OrbOptions options = orb;
  options.parallel = false;  // parallel over images instead
  const OrbExtractor extractor(options);
  std::vector<std::vector<Descriptor>> descriptors(images.size());
  std::atomic<size_t> done{0};
  std::mutex error_mutex;
  std::string error_file;
  constexpr size_t kBatch = 32;  // progress after every batch
  for (size_t begin = 0; begin < images.size(); begin += kBatch) {
    const size_t end = std::min(images.size(), begin + kBatch);
    tbb::parallel_for(tbb::blocked_range<size_t>(begin, end, 1), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i != r.end(); ++i) {
        const cv::Mat image = cv::imread(images[i].string(), cv::IMREAD_GRAYSCALE);
        if (image.empty()) {
          std::lock_guard lock(error_mutex);
          if (error_file.empty()) error_file = images[i].string();
          continue;
        }
        descriptors[i] = extractor.Extract(image).descriptors;
        ++done;
      }
    });
    if (!error_file.empty()) break;
    if (progress) progress(done.load(), images.size());
  }
  if (!error_file.empty()) throw InputError(error_file, "cannot read this image");
  return descriptors;
}

std::vector<std::vector<Descriptor>> ExtractProceduralDescriptors(size_t count, cv::Size size, const OrbOptions& orb,
                                                                  std::uint64_t first_seed,
                                                                  const std::function<void(size_t, size_t)>& progress) {
  OrbOptions options = orb;
  options.parallel = false;
  const OrbExtractor extractor(options);
  std::vector<std::vector<Descriptor>> descriptors(count);
  constexpr size_t kBatch = 32;
  for (size_t begin = 0; begin < count; begin += kBatch) {
    const size_t end = std::min(count, begin + kBatch);
    tbb::parallel_for(tbb::blocked_range<size_t>(begin, end, 1), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i != r.end(); ++i) {
        descriptors[i] = extractor.Extract(MakeSyntheticTrainingImage(first_seed + i, size)).descriptors;
      }
    });
    if (progress) progress(end, count);
  }
  return descriptors;
}

}  // namespace semslam
