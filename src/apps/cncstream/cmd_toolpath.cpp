// `cncstream toolpath PART.stl --tool SPEC --stepover S ... -o part.nc`
#include <chrono>
#include <iostream>
#include <memory>

#include "cncstream/jobs/toolpath_job.hpp"
#include "commands.hpp"
#include "long_job.hpp"
#include "toolpath_options.hpp"

namespace cncstream::app {

void register_toolpath(CLI::App& app, CommandRegistry& registry) {
  struct Opts {
    ToolpathOptions tp;
    std::string out;
    ProgressMode progress = ProgressMode::Auto;
  };
  auto o = std::make_shared<Opts>();
  auto* sub = app.add_subcommand("toolpath", "Generate a raster finishing tool path (G-code) from an STL");
  sub->add_option("stl", o->tp.part.stl, "STL file")->required();
  add_toolpath_options(sub, o->tp);
  sub->add_option("-o,--output", o->out, "G-code file to write")->required();
  add_progress_option(sub, o->progress);
  registry.add(sub, [o] {
    const auto t0 = std::chrono::steady_clock::now();
    jobs::ToolpathParams params = toolpath_params(o->tp);
    params.output = o->out;
    LongJob job(o->progress, o->tp.threads);
    std::optional<jobs::ToolpathProgram> program;
    try {
      program = jobs::generate_toolpath(params, job.control());
    } catch (const jobs::Cancelled&) {
      return job.interrupted_exit(o->out + " not written");
    }
    job.clear_progress();
    const jobs::ToolpathProgram& r = *program;
    std::cout << toolpath_report(r);
    std::cout << "wrote " << o->out << " in "
              << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() << " s total\n";
    return 0;
  });
}

}  // namespace cncstream::app
