#pragma once
// The finishing tool path job: part (STL or mesh) and cutter -> CL engine,
// zig-zag raster on the G-code's lattice, G-code program. Shared by
// `cncstream toolpath` and the main streaming command.
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>

#include "cncstream/cam/cutter.hpp"
#include "cncstream/cam/raster.hpp"
#include "cncstream/gcode/finishing_program.hpp"
#include "cncstream/geometry/mesh.hpp"
#include "cncstream/jobs/height_preview.hpp"
#include "cncstream/jobs/job_control.hpp"
#include "cncstream/jobs/part_source.hpp"

namespace cncstream::jobs {

struct ToolpathParams {
  PartSource part;
  Cutter cutter;
  double stepover = 0.4;
  double step = 0;  // along a row; 0: min(stepover / 4, 0.1)
  RasterDirection direction = RasterDirection::X;
  double feed = 1000, plunge_feed = 300;  // mm/min
  double rpm = 18000;                     // 0: no spindle commands
  std::optional<double> safe_z;           // work coordinates; default 5 mm above the part's top
  double tolerance = 0.002;               // merged points stay within this above the CL, mm
  // Arcs (G2/G3 in the rows' upright planes) where they fit within the
  // tolerance, less the controller's own arc tolerance (GRBL $12), which its
  // chords take.
  bool arcs = true;
  double controller_arc_tolerance = 0.002;  // mm
  std::optional<XYBounds> bounds;         // of the tool tip, model coordinates; default: part box grown by the radius
  std::optional<double> floor;            // lowest tip height, model coordinates; default: the part's lowest z
  XYOrigin origin = XYOrigin::PartMin;
  ZZero z_zero = ZZero::PartTop;
  // Not empty: the program is written there (whole or not at all) as the
  // job's last stage.
  std::filesystem::path output;
};

struct ToolpathProgram {
  std::string gcode;
  ProgramStats stats;
  RasterPath path;
  Cutter cutter;
  std::size_t facets = 0;
  Vec3 work_offset;  // model -> work coordinates
  Mesh work_mesh;    // the part placed in work coordinates (for a verify)
  // The CL grid the rows were sampled from, resampled small (at most
  // kPreviewSideMax nodes a side) in work coordinates, for a preview; the
  // full grid is not kept (path.grid is empty).
  HeightPreview preview;
  double seconds_load = 0, seconds_path = 0, seconds_gcode = 0;
};

// Stages: "load", "tool path", "G-code", "write" (with an output), "done".
// Throws Cancelled on a stop request.
ToolpathProgram generate_toolpath(const ToolpathParams& params, const JobControl& control = {});

}  // namespace cncstream::jobs
