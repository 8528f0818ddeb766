#pragma once
// Colours for the classes a map holds, as plots and the report show them: the Cityscapes palette, except where
// two classes present would look alike (car, truck, bus, train and motorcycle are five dark blues), where the
// rarer class takes a distinct colour instead; and which classes a legend lists.

#include <array>
#include <cstddef>
#include <vector>

#include "semslam/semantics/class_table.h"

namespace semslam {

struct ClassDisplay {
  std::array<Rgb, kNumClasses> color{};         // per trainId
  std::array<bool, kNumClasses> listed{};       // present with at least min_share of the labeled points
  Rgb other{150, 150, 150};                     // unlabeled points and classes not listed
};

// `counts[c]`: points of trainId c. Classes below `min_share` of the labeled points are not listed (and plots
// draw them in `other`, as "other classes"); the colours of listed classes differ by at least min_delta_e (CIE76)
// from each other.
ClassDisplay MakeClassDisplay(const std::array<long long, kNumClasses>& counts, double min_share = 0.005,
                              double min_delta_e = 20.0);

// CIE76 colour difference between two sRGB colours.
double DeltaE(const Rgb& a, const Rgb& b);

}  // namespace semslam
