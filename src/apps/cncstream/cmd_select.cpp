// `cncstream select PART.stl --tools ball:D,bull:D:r --stepover S -o report/`:
// which cutter removes more material where (thesis chapter 4), the scallops
// each leaves, and the report (JSON, CSV, PNG maps).
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "selection_job.hpp"

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
    const SelectionResult r = run_selection(o->sel);
    std::cout << r.table();
    for (const auto& f : write_selection_report(r, o->out)) std::cout << "wrote " << f.string() << "\n";
    return 0;
  });
}

}  // namespace cncstream::app
