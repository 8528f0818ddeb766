#include "semslam/semantics/neighbour_labels.h"

#include <array>
#include <nanoflann.hpp>
#include <vector>

#include "semslam/core/error.h"

namespace semslam {

void NeighbourLabelOptions::Check() const {
  Require(neighbours >= 1, "NeighbourLabelOptions: neighbours must be >= 1");
  Require(confident > 0.0f && confident <= 1.0f, "NeighbourLabelOptions: confident must be in (0, 1]");
  Require(min_votes >= 1 && min_votes <= neighbours, "NeighbourLabelOptions: min_votes must be in 1..neighbours");
  Require(agreement > 0.5 && agreement <= 1.0, "NeighbourLabelOptions: agreement must be in (0.5, 1]");
  Require(alpha >= 1.0f / kNumClasses && alpha <= 1.0f, "NeighbourLabelOptions: alpha must be in [1/19, 1]");
  Require(weight > 0.0f, "NeighbourLabelOptions: weight must be > 0");
}

namespace {

struct Cloud {
  std::vector<Eigen::Vector3d> points;
  size_t kdtree_get_point_count() const { return points.size(); }
  double kdtree_get_pt(size_t index, size_t dim) const { return points[index][static_cast<Eigen::Index>(dim)]; }
  template <class BBox>
  bool kdtree_get_bbox(BBox& /*bb*/) const {
    return false;
  }
};

using KdTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud>, Cloud, 3, size_t>;

}  // namespace

size_t FuseNeighbourLabels(std::span<const Eigen::Vector3d> positions, std::span<LabelDistribution* const> labels,
                           const NeighbourLabelOptions& options) {
  options.Check();
  Require(positions.size() == labels.size(), "FuseNeighbourLabels: positions and labels differ in size");
  // The labelled points, their classes and whether they are confident enough to vote (before any change).
  Cloud cloud;
  std::vector<size_t> index;  // cloud -> input
  std::vector<int> label;
  std::vector<bool> votes;
  for (size_t i = 0; i < positions.size(); ++i) {
    if (labels[i] == nullptr || !labels[i]->HasObservations() || !positions[i].allFinite()) continue;
    cloud.points.push_back(positions[i]);
    index.push_back(i);
    label.push_back(labels[i]->Label());
    votes.push_back(labels[i]->Confidence() >= options.confident);
  }
  if (cloud.points.size() < 2) return 0;
  KdTree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();
  const size_t k = std::min(static_cast<size_t>(options.neighbours) + 1, cloud.points.size());
  std::vector<size_t> found(k);
  std::vector<double> distances(k);
  std::vector<std::pair<size_t, int>> helped;  // cloud index, class
  for (size_t i = 0; i < cloud.points.size(); ++i) {
    if (votes[i]) continue;
    const size_t n = tree.knnSearch(cloud.points[i].data(), k, found.data(), distances.data());
    std::array<int, kNumClasses> count{};
    int total = 0;
    for (size_t j = 0; j < n; ++j) {
      if (found[j] == i || !votes[found[j]]) continue;
      ++count[static_cast<size_t>(label[found[j]])];
      ++total;
    }
    if (total < options.min_votes) continue;
    const auto best = std::max_element(count.begin(), count.end());
    if (*best < options.agreement * total) continue;
    helped.emplace_back(i, static_cast<int>(best - count.begin()));
  }
  for (const auto& [i, cls] : helped) {
    ClassLogProbs observation = ConfusionLogProbs(cls, options.alpha);
    for (float& v : observation) v *= options.weight;
    labels[index[i]]->Fuse(observation);
  }
  return helped.size();
}

}  // namespace semslam
