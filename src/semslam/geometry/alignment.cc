#include "semslam/geometry/alignment.h"

#include <Eigen/SVD>
#include <cmath>

namespace semslam {
namespace {

std::optional<Sim3d> Umeyama(const Points3d& src, const Points3d& tgt, const std::vector<double>& weights,
                             bool with_scale) {
  const size_t n = src.size();
  if (n < 3 || tgt.size() != n || (!weights.empty() && weights.size() != n)) return std::nullopt;
  double total_weight = 0.0;
  Eigen::Vector3d mean_src = Eigen::Vector3d::Zero();
  Eigen::Vector3d mean_tgt = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < n; ++i) {
    const double w = weights.empty() ? 1.0 : weights[i];
    if (!(w >= 0) || !src[i].allFinite() || !tgt[i].allFinite()) return std::nullopt;
    total_weight += w;
    mean_src += w * src[i];
    mean_tgt += w * tgt[i];
  }
  if (total_weight <= 0) return std::nullopt;
  mean_src /= total_weight;
  mean_tgt /= total_weight;

  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  double src_variance = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const double w = weights.empty() ? 1.0 : weights[i];
    const Eigen::Vector3d s = src[i] - mean_src;
    covariance += w * (tgt[i] - mean_tgt) * s.transpose();
    src_variance += w * s.squaredNorm();
  }
  covariance /= total_weight;
  src_variance /= total_weight;
  if (src_variance < 1e-20) return std::nullopt;

  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d singular = svd.singularValues();
  // Collinear sources leave rotation about their line undetermined: the second singular value vanishes.
  if (singular(1) <= 1e-10 * std::max(singular(0), 1e-300)) return std::nullopt;
  Eigen::Vector3d sign(1.0, 1.0, 1.0);
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) sign(2) = -1.0;
  const Eigen::Matrix3d rotation = svd.matrixU() * sign.asDiagonal() * svd.matrixV().transpose();
  const double scale = with_scale ? singular.dot(sign) / src_variance : 1.0;
  if (!(scale > 0) || !std::isfinite(scale)) return std::nullopt;
  const Eigen::Vector3d translation = mean_tgt - scale * rotation * mean_src;
  return Sim3d(scale, Eigen::Quaterniond(rotation), translation);
}

}  // namespace

std::optional<Sim3d> AlignSim3(const Points3d& src, const Points3d& tgt, const std::vector<double>& weights) {
  return Umeyama(src, tgt, weights, /*with_scale=*/true);
}

std::optional<Rigid3d> AlignRigid3(const Points3d& src, const Points3d& tgt, const std::vector<double>& weights) {
  const auto sim = Umeyama(src, tgt, weights, /*with_scale=*/false);
  if (!sim) return std::nullopt;
  return sim->Rigid();
}

double AlignmentRmse(const Sim3d& tgt_from_src, const Points3d& src, const Points3d& tgt) {
  if (src.empty() || src.size() != tgt.size()) return 0.0;
  double sum = 0.0;
  for (size_t i = 0; i < src.size(); ++i) sum += (tgt[i] - tgt_from_src * src[i]).squaredNorm();
  return std::sqrt(sum / static_cast<double>(src.size()));
}

}  // namespace semslam
