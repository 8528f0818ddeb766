#include "semslam/report/class_colors.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace semslam {

namespace {

struct Lab {
  double l, a, b;
};

double Linear(std::uint8_t c) {
  const double v = c / 255.0;
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

Lab ToLab(const Rgb& c) {
  const double r = Linear(c.r), g = Linear(c.g), b = Linear(c.b);
  // sRGB (D65) to XYZ, normalized by the white point.
  const double x = (0.4124 * r + 0.3576 * g + 0.1805 * b) / 0.95047;
  const double y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
  const double z = (0.0193 * r + 0.1192 * g + 0.9505 * b) / 1.08883;
  const auto f = [](double t) { return t > 0.008856 ? std::cbrt(t) : 7.787 * t + 16.0 / 116.0; };
  return {116.0 * f(y) - 16.0, 500.0 * (f(x) - f(y)), 200.0 * (f(y) - f(z))};
}

// Replacements for classes whose Cityscapes colour is taken, well apart from each other and from the palette's
// most common colours (road purple, building grey, vegetation green, sky blue).
constexpr Rgb kSpare[] = {{230, 159, 0},  {0, 158, 115},   {213, 94, 0},    {86, 180, 233}, {204, 121, 167},
                          {0, 114, 178},  {240, 228, 66},  {140, 86, 75},   {23, 190, 207}, {188, 189, 34},
                          {148, 103, 189}, {255, 127, 14}, {44, 160, 44},   {214, 39, 40},  {127, 127, 127}};

}  // namespace

double DeltaE(const Rgb& a, const Rgb& b) {
  const Lab p = ToLab(a), q = ToLab(b);
  return std::sqrt((p.l - q.l) * (p.l - q.l) + (p.a - q.a) * (p.a - q.a) + (p.b - q.b) * (p.b - q.b));
}

ClassDisplay MakeClassDisplay(const std::array<long long, kNumClasses>& counts, double min_share,
                              double min_delta_e) {
  ClassDisplay display;
  for (int c = 0; c < kNumClasses; ++c) display.color[static_cast<size_t>(c)] = ClassColor(c);
  const long long total = std::accumulate(counts.begin(), counts.end(), 0LL);
  std::vector<int> order(kNumClasses);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return counts[static_cast<size_t>(a)] > counts[static_cast<size_t>(b)]; });
  std::vector<Rgb> used = {display.other};
  const auto distinct = [&](const Rgb& c) {
    return std::all_of(used.begin(), used.end(), [&](const Rgb& u) { return DeltaE(c, u) >= min_delta_e; });
  };
  for (const int c : order) {
    const auto n = counts[static_cast<size_t>(c)];
    if (n <= 0 || static_cast<double>(n) < min_share * static_cast<double>(total)) continue;
    display.listed[static_cast<size_t>(c)] = true;
    Rgb& color = display.color[static_cast<size_t>(c)];
    if (!distinct(color)) {
      // The commoner class keeps its Cityscapes colour; this one takes the first spare that is distinct.
      for (const Rgb& spare : kSpare) {
        if (distinct(spare)) {
          color = spare;
          break;
        }
      }
    }
    used.push_back(color);
  }
  return display;
}

}  // namespace semslam
