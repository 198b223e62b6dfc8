#pragma once
// Tool-path generation as the CLI does it: options -> loaded part, CL engine,
// raster path and G-code program with a report. Shared by `toolpath` and by
// the main streaming command.
#include <CLI/CLI.hpp>

#include <optional>
#include <string>

#include "cli_common.hpp"
#include "cncstream/cam/raster.hpp"
#include "cncstream/gcode/finishing_program.hpp"

namespace cncstream::app {

struct ToolpathOptions {
  PartOptions part;
  std::string tool;
  double stepover = 0.4;
  double step = 0;
  std::string direction = "x";
  double feed = 1000;
  double plunge_feed = 300;
  double rpm = 18000;
  std::optional<double> safe_z;
  double tolerance = 0.002;
  std::string bounds;
  std::optional<double> floor;
  std::string origin = "min";
  std::string z_zero = "top";
  unsigned threads = 0;
};

// `tool_required`: false where a G-code file may be given instead of an STL.
void add_toolpath_options(CLI::App* sub, ToolpathOptions& o, bool tool_required = true);

struct ToolpathResult {
  std::string gcode;
  ProgramStats stats;
  RasterPath path;
  Cutter cutter;
  std::size_t facets = 0;
  Vec3 work_offset;  // model -> work coordinates
  Mesh work_mesh;    // the part placed in work coordinates (for a verify)
  double seconds_load = 0, seconds_path = 0, seconds_gcode = 0;
  std::string report() const;  // human-readable summary
};

ToolpathResult generate_toolpath(const ToolpathOptions& o);

}  // namespace cncstream::app
