#pragma once
// G-code for a Z-level roughing path (cam/zlevel_roughing.hpp): each pass
// lifted as the path says (straight up, across, straight down: rapids only
// above the stock or over cleared levels), its ramp at the plunge feed, its
// loops at the feed, as arcs (G17) where they fit if arcs are on.
#include <string>

#include "cncstream/cam/zlevel_roughing.hpp"
#include "cncstream/gcode/finishing_program.hpp"
#include "cncstream/gcode/gcode_writer.hpp"

namespace cncstream {

// The body only: the tool starts at params.safe_z (work coordinates) and is
// left there. Adds to `stats` (lines and bounds are the caller's). Throws
// std::invalid_argument for bad feeds, an empty path, or a safe Z below the
// path's clearance height.
void write_roughing(GcodeWriter& w, const cam::RoughingPath& path, const geometry::Vec3& offset, const MachiningParams& params,
                    ProgramStats& stats);

// A whole program like finishing_program: header, tool, spindle, the body,
// spindle off, program end.
std::string roughing_program(const cam::RoughingPath& path, const geometry::Vec3& offset, const MachiningParams& params,
                             ProgramStats* stats = nullptr);

}  // namespace cncstream
