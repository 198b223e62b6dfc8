#pragma once
// The part a job machines: an STL file read with its units and scale, or a
// mesh already in memory (a daemon that keeps parts loaded).
#include <memory>
#include <string>

#include "cncstream/geometry/mesh.hpp"
#include "cncstream/geometry/stl.hpp"

namespace cncstream::jobs {

struct PartSource {
  std::string stl;  // read unless `mesh` is given; names the part in G-code headers and reports either way
  geometry::LengthUnit units = geometry::LengthUnit::Millimetre;
  double scale = 1.0;                // after the unit conversion
  std::shared_ptr<const geometry::Mesh> mesh;  // already loaded, model coordinates in mm
  double max_extent_mm = 3000;       // larger parts are refused (jobs/size_limits.hpp)
};

// The mesh: `mesh` if given, else the STL read. Throws StlError naming the
// file when it holds no facet with area (nothing to machine), and
// std::invalid_argument when it is larger than max_extent_mm.
std::shared_ptr<const geometry::Mesh> load_part(const PartSource& part);

}  // namespace cncstream::jobs
