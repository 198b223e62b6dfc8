// `cncstream select PART.stl --tools ball:D,bull:D:r --stepover S -o report/`:
// which cutter removes more material where (thesis chapter 4), the scallops
// each leaves, and the report (JSON, CSV, PNG maps).
#include <iostream>
#include <memory>

#include "cncstream/jobs/selection_job.hpp"
#include "cncstream/jobs/selection_report.hpp"
#include "commands.hpp"
#include "selection_options.hpp"

namespace cncstream::app {

void register_select(CLI::App& app, CommandRegistry& registry) {
  struct Opts {
    SelectionOptions sel;
    std::string out = "selection";
  };
  auto o = std::make_shared<Opts>();
  auto* sub = app.add_subcommand("select", "Ball vs radiused cutter: material removal and scallop height per point, with maps");
  add_selection_options(sub, o->sel);
  sub->add_option("-o,--output", o->out, "Report folder")->capture_default_str();
  registry.add(sub, [o] {
    const jobs::JobControl control = thread_limited(o->sel.threads);
    const jobs::SelectionResult r = jobs::run_selection(selection_params(o->sel), control);
    std::cout << r.table();
    jobs::SelectionReportOptions ro;
    ro.nodes_csv = o->sel.nodes_csv;
    for (const auto& f : jobs::write_selection_report(r, o->out, ro, control)) std::cout << "wrote " << f.string() << "\n";
    return 0;
  });
}

}  // namespace cncstream::app
