#pragma once
#include <CLI/CLI.hpp>

#include <functional>
#include <vector>

namespace cncstream::app {

// Each subcommand registers its CLI11 options and a runner; main() runs the
// one that was parsed.
class CommandRegistry {
 public:
  void add(CLI::App* sub, std::function<int()> run) { entries_.push_back({sub, std::move(run)}); }
  int run(const CLI::App& app) const {
    for (const auto& e : entries_)
      if (e.sub->parsed()) return e.run();
    std::cout << app.help();
    return 0;
  }

 private:
  struct Entry {
    CLI::App* sub;
    std::function<int()> run;
  };
  std::vector<Entry> entries_;
};

void register_info(CLI::App& app, CommandRegistry& registry);
void register_toolpath(CLI::App& app, CommandRegistry& registry);
void register_clgrid(CLI::App& app, CommandRegistry& registry);
void register_ports(CLI::App& app, CommandRegistry& registry);
void register_jobs(CLI::App& app, CommandRegistry& registry);
void register_stream(CLI::App& app, CommandRegistry& registry);
void register_select(CLI::App& app, CommandRegistry& registry);
void register_plan(CLI::App& app, CommandRegistry& registry);
void register_resume(CLI::App& app, CommandRegistry& registry);
void register_pendant(CLI::App& app, CommandRegistry& registry);
void register_jog(CLI::App& app, CommandRegistry& registry);
void register_status(CLI::App& app, CommandRegistry& registry);
void register_view(CLI::App& app, CommandRegistry& registry);
void register_probe(CLI::App& app, CommandRegistry& registry);
void register_outline(CLI::App& app, CommandRegistry& registry);
void register_toolchange(CLI::App& app, CommandRegistry& registry);
void register_tools(CLI::App& app, CommandRegistry& registry);
void register_shop(CLI::App& app, CommandRegistry& registry);

}  // namespace cncstream::app
