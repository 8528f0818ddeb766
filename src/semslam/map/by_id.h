#pragma once
// Orders keyframes and map points by id, so that containers of them iterate the same way on every run
// (pointer order would make results depend on memory addresses).

namespace semslam {

struct ById {
  template <typename T>
  bool operator()(const T* a, const T* b) const {
    return a->id() < b->id();
  }
};

}  // namespace semslam
