#pragma once
// Single-point drop queries (height_at): a uniform XY bucket grid in which
// every drawn primitive is listed in each cell its footprint touches, highest
// first, so a query reads one cell and stops at the first primitive whose top
// is not above the best height found.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "cl_contact.hpp"
#include "cl_primitives.hpp"
#include "cncstream/cam/sampled_line.hpp"
#include "cncstream/geometry/mesh.hpp"

namespace cncstream::cam::cl_detail {

class PointIndex {
 public:
  // `faces`: face_offset of each of prims.faces (kept by reference).
  PointIndex(const geometry::Mesh& mesh, const ClPrimitives& prims, const std::vector<FaceOffset>& faces,
             const CutterShape& cutter);
  // Max drop height at (x, y), or kNoContact.
  double drop(double x, double y) const;
  // The first k in [k0, k1] whose point's drop exceeds `limit`, else
  // k1 + 1 (ClEngine::first_above).
  std::size_t first_above(const SampledLine& line, std::size_t k0, std::size_t k1, double limit) const;
  std::size_t entries() const { return entries_.size(); }

 private:
  enum Kind : std::uint32_t { kFace = 0, kEdge = 1u << 30, kVertex = 2u << 30 };
  static constexpr std::uint32_t kIdMask = (1u << 30) - 1;
  double top(std::uint32_t item) const;
  double evaluate(std::uint32_t item, double x, double y, double best) const;
  // The most the item's drop can be anywhere in [xa, xb] x [ya, yb]
  // (rounded up), kNoContact where it cannot touch there.
  double box_bound(std::uint32_t item, double xa, double ya, double xb, double yb) const;
  // The cell holding (x, y), or npos outside the index.
  static constexpr std::size_t npos = static_cast<std::size_t>(-1);
  std::size_t cell_at(double x, double y) const;

  const geometry::Mesh& mesh_;
  const ClPrimitives& prims_;
  CutterShape cutter_;
  double x0_ = 0, y0_ = 0, cell_ = 1;
  std::size_t nx_ = 0, ny_ = 0;
  // A cell's items, each with the most it can give in the cell (rounded up),
  // so a query reads no vertex and stops early.
  struct Entry {
    std::uint32_t item;
    float bound;
  };
  std::vector<std::uint32_t> offset_;  // cell k: entries_[offset_[k], offset_[k + 1])
  std::vector<Entry> entries_;
  // Prepared once: a query evaluates many primitives, and preparing them
  // (square roots, normals) costs more than evaluating them.
  const std::vector<FaceOffset>& faces_;
  std::vector<EdgeGeom> edges_;
};

}  // namespace cncstream::cam::cl_detail
