// Bodies joined into groups by joints: a union-find (path halving), for the loops of a
// model (lineage.cpp), its chains (chains.cpp) and its joint islands (sim_build.cpp).
#pragma once

#include <cstddef>
#include <numeric>
#include <vector>

namespace afhub::physics {

class BodyGroups {
 public:
  explicit BodyGroups(std::size_t bodies) : parent_(bodies) {
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  // The body that stands for `body`'s group.
  int root(int body) noexcept {
    while (parent_[body] != body) body = parent_[body] = parent_[parent_[body]];
    return body;
  }
  // Joins the groups of `a` and `b`; false when they were one group already.
  bool join(int a, int b) noexcept {
    a = root(a);
    b = root(b);
    if (a == b) return false;
    parent_[a] = b;
    return true;
  }

 private:
  std::vector<int> parent_;
};

}  // namespace afhub::physics
