#pragma once
// The cutter-selection options as the CLI takes them (`cncstream select` and
// `plan`), turned into the jobs layer's parameters.
#include <CLI/CLI.hpp>

#include <string>

#include "cli_common.hpp"
#include "cncstream/jobs/job_control.hpp"
#include "cncstream/jobs/plan_job.hpp"
#include "cncstream/jobs/selection_job.hpp"

namespace cncstream::app {

struct SelectionOptions {
  PartOptions part;
  std::string tools = "ball:3.175,bull:3.175:0.79";
  double stepover = 0.4;
  double step = 0.05;      // along the passes
  std::string direction = "x";
  double scallop_tol = 0.01;
  double reach_pitch = -1; // reach-limit lattice, mm; 0: no scallop/unreachable split; < 0: min(0.15, stepover/3)
  double feed = 1000, plunge_feed = 300, rpm = 18000;  // plan only
  double max_rate = 500, accel = 10;  // plan only: for predicted times ($110-$112, $120-$122)
  unsigned threads = 0;
  bool nodes_csv = false;  // also write every CL point's heights, d and choices (large)
  std::string tool_library;  // --tools may name library tools; empty: the default library
  // plan only: feeds and speeds per cutter from a material (tool_choice.hpp).
  std::string material;
  double spindle_max = 24000;
  bool feed_given = false, rpm_given = false, plunge_feed_given = false;
};

void add_selection_options(CLI::App* sub, SelectionOptions& o);

// Throws for a --tools that is not one ball and one radiused cutter.
jobs::SelectionParams selection_params(const SelectionOptions& o);
// With a material: each cutter's feeds and rpm (what the operator did not
// give), and `feeds_report` (if not null) gets the plan's feeds text.
jobs::PlanParams plan_params(const SelectionOptions& o, std::string* feeds_report = nullptr);

}  // namespace cncstream::app
