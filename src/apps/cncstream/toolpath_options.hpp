#pragma once
// The tool path options as the CLI takes them (`toolpath` and the main
// streaming command), turned into the jobs layer's parameters, and the
// report printed after a tool path job.
#include <CLI/CLI.hpp>

#include <optional>
#include <string>

#include "cli_common.hpp"
#include "job_display.hpp"
#include "cncstream/jobs/job_control.hpp"
#include "cncstream/jobs/toolpath_job.hpp"

namespace cncstream::app {

struct ToolpathOptions {
  PartOptions part;
  std::string tool;
  double stepover = 0.4;
  double step = 0;
  std::string direction = "x";
  std::string strategy = "steep-shallow";
  double steep_angle = 45;
  std::optional<double> scallop;
  double feed = 1000;
  double plunge_feed = 300;
  double rpm = 18000;
  std::optional<double> safe_z;
  double tolerance = jobs::kDefaultTolerance;
  std::string arcs = "on";
  double controller_arc_tolerance = 0.002;
  std::string bounds;
  std::optional<double> floor;
  std::string origin = "min";
  std::string z_zero = "top";
  unsigned threads = 0;
  // Stock and depth of cut (roughing first where the finishing pass would cut too deep).
  std::string stock = "auto";
  std::string work_origin;  // X,Y,Z: machine coordinates of this job's work zero (places a saved stock)
  std::optional<double> max_depth;
  std::string rough;
  std::string rest;
  std::optional<double> rough_max_depth;
  double leave = 0.3;
  std::optional<double> step_down;
  double rough_stepover = 0;
  std::optional<double> rough_feed;
  std::string tool_change = "m0";
  // The link the program streams over (--link-rate): bytes/s, NNNbaud or usb.
  // Set: F is lowered where the link cannot deliver a stretch in time, and
  // the ETA uses it. Empty: the feeds as commanded; the ETA uses the profile's.
  std::string link_rate;
  // The tool library and feeds and speeds (tool_choice.hpp): --tool, --rough
  // and --rest may name a library tool; --material computes what the
  // operator did not give (the *_given flags: set when given on the command line).
  std::string tool_library;  // empty: tooling::default_tool_library_path()
  std::string material;
  int flutes = 0;            // a spec's flutes; 0: 2 (a library tool has its own)
  double spindle_max = 0, spindle_min = 0;  // rpm ($30, $31); 0: the machine's, else 24,000 and none
  // Set by resolve_tool_options: the library's numbers of --tool, --rough and
  // --rest (the program's T words); unset for a spec.
  std::optional<int> tool_number, rough_tool_number, rest_tool_number;
  double max_feed = 0;       // mm/min ($110/$111); 0: not known
  double max_feed_z = 0;     // mm/min ($112); 0: not known
  bool feed_given = false, plunge_feed_given = false, rpm_given = false;
};


// `tool_required`: false where a G-code file may be given instead of an STL.
void add_toolpath_options(CLI::App* sub, ToolpathOptions& o, bool tool_required = true);

// Throws for a bad cutter spec or bounds (before the part is read).
jobs::ToolpathParams toolpath_params(const ToolpathOptions& o);

// The program's operations, a line each (tool, operation, lines, time),
// then the plan's notes. `eta` (the planner's estimate per file line) gives
// each operation's time; without it, its feed time (no acceleration).
std::string operations_text(const jobs::ToolpathProgram& r, const EtaEstimator* eta = nullptr);

// Human-readable summary of a finished tool path.
std::string toolpath_report(const jobs::ToolpathProgram& r);

}  // namespace cncstream::app
