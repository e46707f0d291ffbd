// Surface samples bucketed in cubic cells of edge r: the samples within r of a point lie in its
// cell or the 26 around it. Shared by the model's surface (normals) and synthesis (regions).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "fba/grasp/synthesis.hpp"
#include "parallel.hpp"

namespace fba::grasp {

class NeighbourGrid {
 public:
  NeighbourGrid(std::span<const SurfaceSample> s, double r) : r_(r) {
    positions_.reserve(s.size());
    for (std::size_t i = 0; i < s.size(); ++i) {
      // Cell indices must fit the key's 21 bits per axis (and an int): metres over a sane cell size.
      // (allFinite first: Eigen's maxCoeff may pass over a NaN.)
      if (!s[i].position.allFinite() || !((s[i].position.cwiseAbs() / r).maxCoeff() < 1e6))
        throw std::invalid_argument("surface sample " + std::to_string(i) + " is not finite or lies more than 10^6 grid cells (" +
                                    std::to_string(r) + " m) from the origin; expected metres and a cell size near the sample spacing");
      cells_[key(cell(s[i].position))].push_back(i);
      positions_.push_back(s[i].position);
    }
  }

  // For each sample, the samples within r of it (itself too, or not): the 27 cells around its own
  // in x-major order (x outermost, z innermost), each cell's samples in index order. The cells
  // around are looked up once per cell, not once per sample; the cells are done at once with a
  // parallel_for (each writes only its own samples' lists).
  std::vector<std::vector<std::size_t>> neighbourhoods(bool with_self, const ParallelFor& parallel_for = {}) const {
    std::vector<std::vector<std::size_t>> out(positions_.size());
    std::vector<const std::vector<std::size_t>*> cells;
    cells.reserve(cells_.size());
    for (const auto& [k, members] : cells_) cells.push_back(&members);
    for_each_chunk(parallel_for, cells.size(), [&](std::size_t begin, std::size_t end) {
      std::vector<std::size_t> found;
      for (std::size_t ci = begin; ci < end; ++ci) fill(*cells[ci], with_self, found, out);
    });
    return out;
  }

  // f(indices) for each cell's samples, in no order.
  template <typename F>
  void for_each_cell(F f) const {
    for (const auto& [key, members] : cells_) f(members);
  }

 private:
  // The neighbourhoods of one cell's members, each gathered in `found` (reused) and then copied
  // into one allocation of its size.
  void fill(const std::vector<std::size_t>& members, bool with_self, std::vector<std::size_t>& found,
            std::vector<std::vector<std::size_t>>& out) const {
    std::array<const std::vector<std::size_t>*, 27> around{};
    const Eigen::Vector3i c = cell(positions_[members.front()]);
    std::size_t m = 0;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = cells_.find(key(c + Eigen::Vector3i(dx, dy, dz)));
          around[m++] = it == cells_.end() ? nullptr : &it->second;
        }
    for (std::size_t i : members) {
      const Eigen::Vector3d& p = positions_[i];
      found.clear();
      for (const auto* near : around)
        if (near)
          for (std::size_t j : *near)
            if ((with_self || j != i) && (positions_[j] - p).squaredNorm() <= r_ * r_) found.push_back(j);
      out[i].assign(found.begin(), found.end());
    }
  }

  Eigen::Vector3i cell(const Eigen::Vector3d& p) const { return (p / r_).array().floor().cast<int>(); }
  static std::uint64_t key(const Eigen::Vector3i& c) {
    return (static_cast<std::uint64_t>(c.x() & 0x1fffff) << 42) | (static_cast<std::uint64_t>(c.y() & 0x1fffff) << 21) |
           static_cast<std::uint64_t>(c.z() & 0x1fffff);
  }
  double r_;
  // The samples' positions alone, packed: the search reads nothing else of a sample.
  std::vector<Eigen::Vector3d> positions_;
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> cells_;
};

}  // namespace fba::grasp
