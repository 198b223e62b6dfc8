#pragma once
// Where the part sits in work coordinates and the lattice its tool paths lie
// on, shared by every job that writes G-code (tool path, selection, plan):
// path XY on the G-code's decimal grid in work coordinates, so the printed
// coordinates are exactly where the path was computed and checked.
#include "cncstream/cam/raster.hpp"
#include "cncstream/gcode/finishing_program.hpp"
#include "cncstream/geometry/mesh.hpp"

namespace cncstream::jobs {

struct WorkSetup {
  geometry::Vec3 offset;        // model -> work coordinates
  cam::XYLattice lattice;  // the G-code's grid (10^-decimals mm), placed on the work origin, in model coordinates
};

// `decimals`: those the G-code prints (MachiningParams::decimals).
WorkSetup work_setup(const geometry::Box3& part, XYOrigin xy = XYOrigin::PartMin, ZZero z = ZZero::PartTop,
                     int decimals = MachiningParams{}.decimals);

}  // namespace cncstream::jobs
