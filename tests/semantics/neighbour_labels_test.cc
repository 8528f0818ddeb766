// A weak label follows its confident neighbours; confident labels and split neighbourhoods are left alone.

#include "semslam/semantics/neighbour_labels.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "semslam/core/error.h"

namespace semslam {
namespace {

constexpr int kRoad = 0, kBuilding = 2, kCar = 13;

LabelDistribution Observed(std::initializer_list<int> classes) {
  LabelDistribution d;
  for (int c : classes) d.FuseLabel(c, 0.75f);
  return d;
}

struct Scene {
  std::vector<Eigen::Vector3d> positions;
  std::vector<LabelDistribution> labels;
  std::vector<LabelDistribution*> Pointers() {
    std::vector<LabelDistribution*> p;
    for (auto& l : labels) p.push_back(&l);
    return p;
  }
};

// A 5x5 wall of confident building points at x = 0..4 and a 5x5 patch of road at x = 10..14, one point each
// at the given places with the given observations.
Scene Wall(const std::vector<std::pair<Eigen::Vector3d, LabelDistribution>>& extra) {
  Scene s;
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 5; ++j) {
      s.positions.emplace_back(i, j, 0.0);
      s.labels.push_back(Observed({kBuilding, kBuilding, kBuilding}));
      s.positions.emplace_back(10 + i, j, 0.0);
      s.labels.push_back(Observed({kRoad, kRoad, kRoad}));
    }
  }
  for (const auto& [p, l] : extra) {
    s.positions.push_back(p);
    s.labels.push_back(l);
  }
  return s;
}

TEST(NeighbourLabels, AWeakLabelFollowsItsConfidentNeighbours) {
  Scene s = Wall({{{2.1, 2.1, 0.1}, Observed({kCar})},             // one wrong observation
                  {{2.2, 1.1, 0.1}, Observed({kCar, kBuilding})},  // a tie
                  {{12.1, 2.1, 0.1}, Observed({kCar, kCar, kCar})},  // confident: kept
                  {{7.0, 2.0, 0.0}, Observed({kCar})}});             // between the two: split votes, kept
  auto pointers = s.Pointers();
  EXPECT_EQ(FuseNeighbourLabels(s.positions, pointers), 2u);
  const size_t n = s.labels.size();
  EXPECT_EQ(s.labels[n - 4].Label(), kBuilding);
  EXPECT_EQ(s.labels[n - 3].Label(), kBuilding);
  EXPECT_EQ(s.labels[n - 2].Label(), kCar);
  EXPECT_EQ(s.labels[n - 1].Label(), kCar);
  EXPECT_EQ(s.labels[n - 4].NumObservations(), 2);  // the neighbourhood counts as one more observation
  EXPECT_EQ(s.labels[0].Label(), kBuilding);
  EXPECT_EQ(s.labels[0].NumObservations(), 3);
}

TEST(NeighbourLabels, TheOrderOfThePointsDoesNotMatter) {
  // Two weak points next to each other: neither votes for the other, whichever comes first.
  Scene a = Wall({{{2.1, 2.1, 0.1}, Observed({kCar})}, {{2.2, 2.2, 0.1}, Observed({kCar})}});
  Scene b = a;
  std::reverse(b.positions.begin(), b.positions.end());
  std::reverse(b.labels.begin(), b.labels.end());
  auto pa = a.Pointers(), pb = b.Pointers();
  EXPECT_EQ(FuseNeighbourLabels(a.positions, pa), FuseNeighbourLabels(b.positions, pb));
  for (size_t i = 0; i < a.labels.size(); ++i) {
    EXPECT_EQ(a.labels[i].Label(), b.labels[a.labels.size() - 1 - i].Label()) << i;
  }
}

TEST(NeighbourLabels, BadInputIsRefused) {
  std::vector<Eigen::Vector3d> positions(2, Eigen::Vector3d::Zero());
  std::vector<LabelDistribution*> labels(1, nullptr);
  EXPECT_THROW(FuseNeighbourLabels(positions, labels), InvalidArgument);
  NeighbourLabelOptions options;
  options.min_votes = 20;
  EXPECT_THROW(options.Check(), InvalidArgument);
  // Nothing labelled: nothing to do.
  std::vector<LabelDistribution> empty(2);
  std::vector<LabelDistribution*> pointers{&empty[0], &empty[1]};
  EXPECT_EQ(FuseNeighbourLabels(positions, pointers), 0u);
}

}  // namespace
}  // namespace semslam
