// cncstream: the operator's command. Subcommands are registered by the
// files of this folder (one concern each); main only wires them up.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>
#include <exception>
#include <iostream>

#include "commands.hpp"

namespace {

int run_cncstream(int argc, char** argv) {
  CLI::App app{"cncstream: tool paths from STL and G-code streaming for 3-axis CNC routers"};
  app.require_subcommand(0, 1);
  cncstream::app::CommandRegistry registry;
  cncstream::app::register_info(app, registry);
  cncstream::app::register_clgrid(app, registry);
  cncstream::app::register_toolpath(app, registry);
  cncstream::app::register_ports(app, registry);
  cncstream::app::register_jobs(app, registry);
  cncstream::app::register_stream(app, registry);
  cncstream::app::register_resume(app, registry);
  cncstream::app::register_select(app, registry);
  cncstream::app::register_plan(app, registry);
  cncstream::app::register_pendant(app, registry);
  cncstream::app::register_jog(app, registry);
  cncstream::app::register_status(app, registry);
  cncstream::app::register_view(app, registry);
  cncstream::app::register_probe(app, registry);
  cncstream::app::register_outline(app, registry);
  cncstream::app::register_toolchange(app, registry);
  cncstream::app::register_tools(app, registry);
  cncstream::app::register_shop(app, registry);
  // The bare form `cncstream FILE PORT ...` is `cncstream stream FILE PORT ...`:
  // anything first that is neither a subcommand nor an option is a file.
  std::vector<std::string> args(argv + 1, argv + argc);
  if (!args.empty() && !args[0].empty() && args[0][0] != '-') {
    bool known = false;
    for (const auto* sub : app.get_subcommands({}))
      if (sub->check_name(args[0])) known = true;
    if (!known) args.insert(args.begin(), "stream");
  }
  std::reverse(args.begin(), args.end());  // CLI11 takes them last-first
  try {
    app.parse(args);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    return registry.run(app);
  } catch (const std::exception& e) {
    std::cerr << "cncstream: error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) {
  // What escapes run_cncstream() (registering the options, or an exception that is not
  // an std::exception) ends the program with a message, not std::terminate.
  try {
    return run_cncstream(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "cncstream: error: " << e.what() << "\n";
  } catch (...) {
    std::cerr << "cncstream: error: an unknown exception\n";
  }
  return 1;
}
