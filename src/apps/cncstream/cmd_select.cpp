// `cncstream select PART.stl --tools ball:D,bull:D:r --stepover S -o report/`:
// which cutter removes more material where (thesis chapter 4), the scallops
// each leaves, and the report (JSON, CSV, PNG maps).
#include <iostream>
#include <memory>

#include "cncstream/jobs/selection_job.hpp"
#include "cncstream/jobs/selection_report.hpp"
#include "commands.hpp"
#include "long_job.hpp"
#include "selection_options.hpp"

namespace cncstream::app {

void register_select(CLI::App& app, CommandRegistry& registry) {
  struct Opts {
    SelectionOptions sel;
    std::string out = "selection";
    ProgressMode progress = ProgressMode::Auto;
  };
  auto o = std::make_shared<Opts>();
  auto* sub = app.add_subcommand("select", "Ball vs radiused cutter: material removal and scallop height per point, with maps");
  add_selection_options(sub, o->sel);
  sub->add_option("-o,--output", o->out, "Report folder")->capture_default_str();
  add_progress_option(sub, o->progress);
  registry.add(sub, [o] {
    LongJob job(o->progress, o->sel.threads);
    const jobs::JobControl control = job.control();
    std::optional<jobs::SelectionResult> result;
    try {
      result = jobs::run_selection(selection_params(o->sel), control);
    } catch (const jobs::Cancelled&) {
      return job.interrupted_exit("no report written in " + o->out);
    }
    const jobs::SelectionResult& r = *result;
    job.clear_progress();
    std::cout << r.table() << std::flush;
    jobs::SelectionReportOptions ro;
    ro.nodes_csv = o->sel.nodes_csv;
    std::vector<std::filesystem::path> files;
    try {
      files = jobs::write_selection_report(r, o->out, ro, control);
    } catch (const jobs::Cancelled&) {
      return job.interrupted_exit("the report in " + o->out + " is incomplete (each file in it is whole)");
    }
    job.clear_progress();
    for (const auto& f : files) std::cout << "wrote " << f.string() << "\n";
    return 0;
  });
}

}  // namespace cncstream::app
