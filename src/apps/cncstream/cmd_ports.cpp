// `cncstream ports`: list serial ports with their USB identity and which one
// `auto` would pick.
#include <iostream>

#include "cncstream/transport/port_discovery.hpp"
#include "commands.hpp"

namespace cncstream::app {

void register_ports(CLI::App& app, CommandRegistry& registry) {
  auto* sub = app.add_subcommand("ports", "List serial ports (USB VID:PID, manufacturer, serial) and the auto choice");
  registry.add(sub, [] {
    const auto ports = transport::list_ports();
    if (ports.empty()) std::cout << "no serial ports found\n";
    for (const auto& p : ports) std::cout << transport::format_port(p) << "\n";
    const auto choice = transport::choose_auto_port(ports);
    std::cout << "\nauto: " << choice.message << "\n";
    return 0;
  });
}

}  // namespace cncstream::app
