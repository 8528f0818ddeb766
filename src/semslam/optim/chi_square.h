#pragma once
// 95 % quantiles of the chi-square distribution, the outlier tests of reprojection errors weighted by the
// inverse variance of their keypoint's pyramid level (Mur-Artal et al. 2015, 2017): 2 DoF for a monocular
// pixel (u, v), 3 DoF for a stereo one (u, v, u_right).

namespace semslam {

inline constexpr double kChi2Mono = 5.991;    // chi2(0.95, 2)
inline constexpr double kChi2Stereo = 7.815;  // chi2(0.95, 3)

}  // namespace semslam
