#include "semslam/features/stereo_matching.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "semslam/core/error.h"

namespace semslam {

void StereoMatchOptions::Check() const {
  Require(std::isfinite(min_depth), "stereo matching: min_depth must be finite");
  Require(max_descriptor_distance >= 0 && max_descriptor_distance <= 256,
          "stereo matching: max_descriptor_distance must be in [0, 256]");
  Require(row_band >= 0.0f, "stereo matching: row_band must be >= 0");
  Require(max_level_difference >= 0, "stereo matching: max_level_difference must be >= 0");
  Require(patch_half_size >= 1 && patch_half_size <= 15,
          "stereo matching: patch_half_size must be in [1, 15]");
  Require(search_half_range >= 1 && search_half_range <= 32,
          "stereo matching: search_half_range must be in [1, 32]");
  Require(outlier_factor > 0.0f, "stereo matching: outlier_factor must be positive");
  Require(ratio > 0.0f && ratio <= 1.0f, "stereo matching: ratio must be in (0, 1]");
}

namespace {

// Right keypoints by image row: row r holds every right keypoint whose row band covers r.
struct RowIndex {
  std::vector<int> start;    // rows + 1
  std::vector<int> entries;  // right keypoint indices

  RowIndex(const FeatureSet& right, int rows, float band) {
    start.assign(static_cast<size_t>(rows) + 1, 0);
    auto range = [&](const Keypoint& kp, int& r0, int& r1) {
      const float r = band * right.pyramid.scale[static_cast<size_t>(kp.level)];
      r0 = std::max(0, static_cast<int>(std::floor(kp.pixel.y() - r)));
      r1 = std::min(rows - 1, static_cast<int>(std::ceil(kp.pixel.y() + r)));
    };
    for (const Keypoint& kp : right.keypoints) {
      int r0, r1;
      range(kp, r0, r1);
      for (int r = r0; r <= r1; ++r) ++start[static_cast<size_t>(r) + 1];
    }
    for (size_t r = 0; r < static_cast<size_t>(rows); ++r) start[r + 1] += start[r];
    entries.resize(static_cast<size_t>(start.back()));
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (size_t j = 0; j < right.keypoints.size(); ++j) {
      int r0, r1;
      range(right.keypoints[j], r0, r1);
      for (int r = r0; r <= r1; ++r)
        entries[static_cast<size_t>(fill[static_cast<size_t>(r)]++)] = static_cast<int>(j);
    }
  }
};

// Mean absolute difference per pixel between the mean-removed patches of `left` at (xl, y) and `right` at
// (xr, y), both (2h+1)^2 and inside their images.
float PatchCost(const cv::Mat& left, int xl, const cv::Mat& right, int xr, int y, int h) {
  const int n = (2 * h + 1) * (2 * h + 1);
  int sum_l = 0, sum_r = 0;
  for (int dy = -h; dy <= h; ++dy) {
    const std::uint8_t* pl = left.ptr<std::uint8_t>(y + dy) + xl;
    const std::uint8_t* pr = right.ptr<std::uint8_t>(y + dy) + xr;
    for (int dx = -h; dx <= h; ++dx) {
      sum_l += pl[dx];
      sum_r += pr[dx];
    }
  }
  // sum |n*L - sum_l - (n*R - sum_r)| / n^2: exact integer arithmetic up to the final division.
  long total = 0;
  const int offset = sum_r - sum_l;
  for (int dy = -h; dy <= h; ++dy) {
    const std::uint8_t* pl = left.ptr<std::uint8_t>(y + dy) + xl;
    const std::uint8_t* pr = right.ptr<std::uint8_t>(y + dy) + xr;
    for (int dx = -h; dx <= h; ++dx) total += std::abs(n * (pl[dx] - pr[dx]) + offset);
  }
  return static_cast<float>(static_cast<double>(total) / (static_cast<double>(n) * n));
}

}  // namespace

StereoMatches MatchStereo(const FeatureSet& left, const FeatureSet& right, const cv::Mat& left_image,
                          const cv::Mat& right_image, const StereoRig& rig,
                          const StereoMatchOptions& options) {
  Require(!left_image.empty() && !right_image.empty() && left_image.size() == right_image.size(),
          "MatchStereo: need two images of the same size");
  cv::Mat left_grey = left_image, right_grey = right_image;
  Require(left_image.type() == CV_8UC1 && right_image.type() == CV_8UC1,
          "MatchStereo: need 8-bit grey images");
  ImagePyramid left_pyramid, right_pyramid;
  tbb::parallel_invoke([&] { left_pyramid = BuildImagePyramid(left_grey, left.pyramid); },
                       [&] { right_pyramid = BuildImagePyramid(right_grey, right.pyramid); });
  return MatchStereo(left, right, left_pyramid, right_pyramid, rig, options);
}

StereoMatches MatchStereo(const FeatureSet& left, const FeatureSet& right, const ImagePyramid& left_pyramid,
                          const ImagePyramid& right_pyramid, const StereoRig& rig,
                          const StereoMatchOptions& options) {
  options.Check();
  rig.Check();
  Require(
      left.keypoints.size() == left.descriptors.size() && right.keypoints.size() == right.descriptors.size(),
      "MatchStereo: keypoints and descriptors differ in number");
  Require(!left_pyramid.empty() && left_pyramid.num_levels() == right_pyramid.num_levels() &&
              left_pyramid.levels[0].size() == right_pyramid.levels[0].size(),
          "MatchStereo: the two pyramids differ");
  Require(left.pyramid.num_levels <= left_pyramid.num_levels() &&
              right.pyramid.num_levels <= right_pyramid.num_levels(),
          "MatchStereo: features have more levels than the pyramids");
  StereoMatches out;
  out.right_u.assign(left.size(), -1.0f);
  out.depth.assign(left.size(), -1.0f);
  if (left.size() == 0 || right.size() == 0) return out;

  const int rows = left_pyramid.levels[0].rows;
  const RowIndex index(right, rows, options.row_band);
  const double fb = rig.FocalBaseline();
  const double min_depth = options.min_depth > 0 ? options.min_depth : rig.baseline;
  const float max_disparity = static_cast<float>(fb / min_depth);
  const int h = options.patch_half_size, range = options.search_half_range;
  std::vector<float> cost(left.size(), -1.0f);

  auto match_one = [&](size_t i) {
    const Keypoint& kl = left.keypoints[i];
    const int row = static_cast<int>(std::lround(kl.pixel.y()));
    if (row < 0 || row >= rows) return;
    const float ul = kl.pixel.x();
    const float min_u = ul - max_disparity, max_u = ul;
    BestTwo best;
    for (int e = index.start[static_cast<size_t>(row)]; e < index.start[static_cast<size_t>(row) + 1]; ++e) {
      const int j = index.entries[static_cast<size_t>(e)];
      const Keypoint& kr = right.keypoints[static_cast<size_t>(j)];
      if (std::abs(kr.level - kl.level) > options.max_level_difference) continue;
      if (kr.pixel.x() < min_u || kr.pixel.x() > max_u) continue;
      best.Offer(j, HammingDistance(left.descriptors[i], right.descriptors[static_cast<size_t>(j)]));
    }
    if (!best.found() || best.best > options.max_descriptor_distance || !best.PassesRatio(options.ratio))
      return;

    // Sub-pixel refinement on the left keypoint's level.
    const int level = kl.level;
    const cv::Mat& li = left_pyramid.levels[static_cast<size_t>(level)];
    const cv::Mat& ri = right_pyramid.levels[static_cast<size_t>(level)];
    const int xl = static_cast<int>(std::lround(left_pyramid.FromLevel0X(ul, level)));
    const int yl = static_cast<int>(std::lround(left_pyramid.FromLevel0Y(kl.pixel.y(), level)));
    const float ur0 = right.keypoints[static_cast<size_t>(best.best_index)].pixel.x();
    const int xr = static_cast<int>(std::lround(right_pyramid.FromLevel0X(ur0, level)));
    if (yl - h < 0 || yl + h >= li.rows || xl - h < 0 || xl + h >= li.cols) return;
    if (xr - range - h < 0 || xr + range + h >= ri.cols) return;
    float costs[2 * 32 + 1];
    int best_shift = 0;
    float best_cost = 1e30f;
    for (int d = -range; d <= range; ++d) {
      const float c = PatchCost(li, xl, ri, xr + d, yl, h);
      costs[d + range] = c;
      if (c < best_cost) {
        best_cost = c;
        best_shift = d;
      }
    }
    if (best_shift == -range || best_shift == range) return;  // minimum at the border: not bracketed
    const float c_minus = costs[best_shift + range - 1], c0 = costs[best_shift + range],
                c_plus = costs[best_shift + range + 1];
    float delta = 0.0f;
    if (options.subpixel_fit == StereoMatchOptions::SubpixelFit::kParabola) {
      const float curvature = c_minus - 2.0f * c0 + c_plus;
      if (!(curvature > 0.0f)) return;
      delta = 0.5f * (c_minus - c_plus) / curvature;
    } else {
      // Lines through the minimum and its higher neighbour, mirrored: they cross at the sub-pixel minimum.
      const float slope = std::max(c_minus, c_plus) - c0;
      if (!(slope > 0.0f)) return;
      delta = 0.5f * (c_minus - c_plus) / slope;
    }
    if (std::abs(delta) > 1.0f) return;
    const float ur_level = static_cast<float>(xr + best_shift) + delta;
    const float ur = right_pyramid.ToLevel0X(ur_level, level);
    const float disparity = ul - ur;
    if (!(disparity > 0.0f) || disparity > max_disparity) return;
    out.right_u[i] = ur;
    out.depth[i] = static_cast<float>(fb / disparity);
    cost[i] = best_cost;
  };
  if (options.parallel) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, left.size(), 64),
                      [&](const tbb::blocked_range<size_t>& r) {
                        for (size_t i = r.begin(); i != r.end(); ++i) match_one(i);
                      });
  } else {
    for (size_t i = 0; i < left.size(); ++i) match_one(i);
  }

  // Outliers: correlation cost far above the median of the matches.
  std::vector<float> costs;
  for (const float c : cost) {
    if (c >= 0.0f) costs.push_back(c);
  }
  if (costs.empty()) return out;
  std::nth_element(costs.begin(), costs.begin() + static_cast<std::ptrdiff_t>(costs.size() / 2), costs.end());
  const float median = costs[costs.size() / 2];
  const float limit = options.outlier_factor * std::max(median, 1.0f);
  for (size_t i = 0; i < left.size(); ++i) {
    if (cost[i] < 0.0f) continue;
    if (cost[i] > limit) {
      out.right_u[i] = -1.0f;
      out.depth[i] = -1.0f;
    } else {
      ++out.num_matched;
    }
  }
  return out;
}

}  // namespace semslam
