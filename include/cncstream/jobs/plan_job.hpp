#pragma once
// The combined-tool plan (`cncstream plan`), the thesis's recommendation made
// real: machine the part with the cutter that removes more material, then
// clean up with the other only where the residual exceeds the tolerance and
// the other does better. One G-code program per tool (GRBL has no M6: the
// operator changes the tool between files), and the predicted machining time
// and largest residual of ball only, radiused only, and combined; and both
// as one job program with the tool change in it.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "cncstream/jobs/job_control.hpp"
#include "cncstream/jobs/selection_job.hpp"

namespace cncstream::jobs {

struct PlanParams {
  // sim_along <= 0 here: min(stepover, max(step, 0.2)), since the clean-up is
  // placed from the simulated residual.
  SelectionParams selection;
  double feed = 1000, plunge_feed = 300, rpm = 18000;
  double max_rate = 500, accel = 10;  // per axis, for predicted times ($110-$112, $120-$122)
  // Set (feeds and speeds from a material): that cutter's operations use
  // these instead of feed, plunge_feed and rpm.
  struct CutterRate {
    double feed = 0, plunge_feed = 0, rpm = 0;
  };
  std::optional<CutterRate> ball_rate, radiused_rate;
};

struct PlanOption {
  std::string name;
  double seconds = 0;
  double max_residual = 0;          // over the part, mm
  double share_above_tol = 0;       // of on-part simulation nodes
  double max_scallop = 0;           // residual less what the option's cutters cannot reach at all
  double scallop_share_above_tol = 0;
};

struct PlanResult {
  PlanParams params;  // with the simulation spacing used
  SelectionResult selection;
  bool radiused_first = false;
  const CutterRun& first() const { return radiused_first ? selection.radiused : selection.ball; }
  const CutterRun& second() const { return radiused_first ? selection.ball : selection.radiused; }
  std::vector<cam::Polyline> cleanup_pieces;  // the second cutter's, model coordinates
  std::string program_first;             // T1: finishing with the first cutter
  std::string program_second;            // T2: the clean-up; empty when none is needed
  // The same as one job (gcode/job_program.hpp): the finishing with T1, the
  // tool change (M0 and the operator's note, or none without a clean-up),
  // the clean-up with T2: one program a streamer pauses in, and resume
  // knows the tool of.
  std::string program_job;
  std::vector<PlanOption> options;       // ball only, radiused only, combined
};

// Stages: the selection's, then "clean-up", "programs", "estimates", "done".
// Throws Cancelled on a stop request.
PlanResult run_plan(const PlanParams& params, const JobControl& control = {});

struct PlanFiles {
  std::filesystem::path first, second;  // second empty when there is no clean-up
  std::filesystem::path job;            // both operations in one program
  std::filesystem::path json;
};

// <part stem>-1-<first cutter>.nc, <part stem>-2-<second cutter>.nc (when
// there is a clean-up), <part stem>-job.nc and plan.json (last) into `dir`
// (created), each whole or not at all.
PlanFiles write_plan(const PlanResult& plan, const std::filesystem::path& dir);

}  // namespace cncstream::jobs
