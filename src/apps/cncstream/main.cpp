// cncstream: the operator's command. Subcommands are registered by the
// files of this folder (one concern each); main only wires them up.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <iostream>

#include "commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"cncstream: tool paths from STL and G-code streaming for 3-axis CNC routers"};
  app.require_subcommand(0, 1);
  cncstream::app::CommandRegistry registry;
  cncstream::app::register_info(app, registry);
  cncstream::app::register_ports(app, registry);
  cncstream::app::register_jobs(app, registry);
  cncstream::app::register_stream(app, registry);
  try {
    app.parse(argc, argv);
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
