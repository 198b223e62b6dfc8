// `cncstream plan PART.stl --tools ball:D,bull:D:r --stepover S --scallop-tol T -o plan/`:
// the thesis's recommendation made real (the plan job: see
// cncstream/jobs/plan_job.hpp). Machine the part with the cutter that removes
// more material, then clean up with the other only where the residual scallop
// exceeds the tolerance. One G-code file per tool, and the predicted
// machining time and largest residual of ball only, radiused only, combined.
#include <iomanip>
#include <iostream>
#include <memory>

#include "cncstream/jobs/plan_job.hpp"
#include "commands.hpp"
#include "job_display.hpp"
#include "long_job.hpp"
#include "selection_options.hpp"
#include "tool_choice.hpp"

namespace cncstream::app {

void register_plan(CLI::App& app, CommandRegistry& registry) {
  struct Opts {
    SelectionOptions sel;
    std::string out = "plan";
    ProgressMode progress = ProgressMode::Auto;
  };
  auto o = std::make_shared<Opts>();
  auto* sub = app.add_subcommand(
      "plan", "Combined-tool plan: the cutter removing more material, then the other only where scallops exceed --scallop-tol");
  add_selection_options(sub, o->sel);
  sub->add_option("--feed", o->sel.feed, "Cutting feed, mm/min (default: from --material, else 1000)")
      ->check(CLI::PositiveNumber)->each([o](const std::string&) { o->sel.feed_given = true; });
  sub->add_option("--plunge-feed", o->sel.plunge_feed, "Plunge feed, mm/min (default: from --material, else 300)")
      ->check(CLI::PositiveNumber)->each([o](const std::string&) { o->sel.plunge_feed_given = true; });
  sub->add_option("--rpm", o->sel.rpm, "Spindle speed (default: from --material, else 18000)")
      ->check(CLI::NonNegativeNumber)->each([o](const std::string&) { o->sel.rpm_given = true; });
  sub->add_option("--material", o->sel.material,
                  "Each cutter's rpm and feeds from chip load for this material (walnut, mdf, acrylic ...), within "
                  "--max-rate and --spindle-max; --feed, --rpm and --plunge-feed win");
  sub->add_option("--spindle-max", o->sel.spindle_max, "The spindle's highest speed, rpm ($30)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  sub->add_option("--max-rate", o->sel.max_rate, "Machine's max rate per axis for the time estimate, mm/min ($110-$112)")
      ->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--accel", o->sel.accel, "Machine's acceleration per axis for the time estimate, mm/s^2 ($120-$122)")
      ->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("-o,--output", o->out, "Folder for the G-code files and plan.json")->capture_default_str();
  add_progress_option(sub, o->progress);
  registry.add(sub, [o] {
    std::string feeds_report;
    const jobs::PlanParams params = plan_params(o->sel, &feeds_report);
    LongJob job(o->progress, o->sel.threads);
    std::optional<jobs::PlanResult> result;
    try {
      result = jobs::run_plan(params, job.control());
    } catch (const jobs::Cancelled&) {
      return job.interrupted_exit("no plan written in " + o->out);
    }
    job.clear_progress();
    const jobs::PlanResult& plan = *result;
    const jobs::SelectionResult& r = plan.selection;
    std::cout << r.table();
    const jobs::PlanFiles files = jobs::write_plan(plan, o->out);
    const jobs::CutterRun& first = plan.first();
    const jobs::CutterRun& second = plan.second();
    const auto& so = plan.params.selection;
    std::cout << "plan (scallop tolerance " << so.scallop_tol << " mm; times at " << params.max_rate << " mm/min, "
              << params.accel << " mm/s^2 per axis):\n";
    std::cout << "  option                                              time      largest residual   nodes above tol"
                 "   largest scallop   scallop above tol\n";
    for (const auto& op : plan.options)
      std::cout << "  " << std::left << std::setw(50) << op.name << std::right << std::setw(9) << format_duration(op.seconds) << "   "
                << std::fixed << std::setprecision(4) << std::setw(10) << op.max_residual << " mm   " << std::setprecision(2)
                << std::setw(10) << 100 * op.share_above_tol << " %" << std::setprecision(4) << std::setw(14)
                << op.max_scallop << " mm" << std::setprecision(2) << std::setw(17) << 100 * op.scallop_share_above_tol
                << " %\n";
    std::cout << "  (residual: all material left; scallop: less what no stepover of these cutters removes, such as gaps "
                 "narrower than the cutter)\n";
    std::cout << std::defaultfloat;
    // Feeds and speeds per cutter (--material): tool, rpm, feed, chip, removal rate.
    std::cout << feeds_report;
    std::cout << "wrote " << files.first.string() << " (" << first.cutter.description() << ")\n";
    if (!plan.cleanup_pieces.empty())
      std::cout << "wrote " << files.second.string() << " (" << second.cutter.description() << ", "
                << plan.cleanup_pieces.size() << " clean-up pieces)\n"
                << "GRBL has no tool changer command: run file 1, then change to the " << second.cutter.description()
                << ", set its Z zero on the part's top again (the tool length differs), and run file 2.\n";
    else
      std::cout << "no clean-up needed: the " << first.cutter.description() << " leaves nothing above the tolerance\n";
    std::cout << "wrote " << files.job.string()
              << (plan.cleanup_pieces.empty() ? " (the same as one job)\n"
                                               : " (both as one job: it pauses for the tool change with the operator's "
                                                 "note, and `cncstream resume` knows which tool is in)\n");
    return 0;
  });
}

}  // namespace cncstream::app
