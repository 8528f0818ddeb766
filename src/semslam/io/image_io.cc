// ReadGreyImage and WritePng (declared in sequence.h).

#include <fmt/format.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <system_error>
#include <vector>

#include "semslam/core/atomic_file.h"
#include "semslam/core/error.h"
#include "semslam/io/sequence.h"

namespace semslam {

namespace fs = std::filesystem;

cv::Mat ReadGreyImage(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(path, "image file not found");
  cv::Mat image = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  if (image.empty()) throw InputError(path, "cannot decode the image (corrupt or not an image)");
  if (image.depth() == CV_16U) {
    image.convertTo(image, CV_8U, 1.0 / 257.0);
  } else if (image.depth() != CV_8U) {
    throw InputError(
        path, fmt::format("unsupported pixel depth (OpenCV depth {}); expected 8 or 16 bit", image.depth()));
  }
  if (image.channels() == 3) {
    cv::cvtColor(image, image, cv::COLOR_BGR2GRAY);
  } else if (image.channels() == 4) {
    cv::cvtColor(image, image, cv::COLOR_BGRA2GRAY);
  } else if (image.channels() != 1) {
    throw InputError(path, fmt::format("unsupported number of channels ({})", image.channels()));
  }
  return image;
}

void WritePng(const fs::path& path, const cv::Mat& image, int compression) {
  Require(!image.empty(), "WritePng: empty image");
  Require(compression >= 0 && compression <= 9, "WritePng: compression must be in 0..9");
  Require(image.depth() == CV_8U || image.depth() == CV_16U, "WritePng: PNG holds 8- or 16-bit images only");
  std::vector<uchar> bytes;
  if (!cv::imencode(".png", image, bytes, {cv::IMWRITE_PNG_COMPRESSION, compression})) {
    throw std::runtime_error(fmt::format("{}: PNG encoding failed", path.string()));
  }
  WriteFileAtomically(path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

}  // namespace semslam
