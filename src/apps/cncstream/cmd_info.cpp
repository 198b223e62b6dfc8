// `cncstream info PART.stl`: load an STL and print what a person wants to know.
#include <iostream>
#include <memory>

#include "cncstream/geometry/stl.hpp"
#include "cncstream/jobs/size_limits.hpp"
#include "cli_common.hpp"
#include "commands.hpp"

namespace cncstream::app {

void register_info(CLI::App& app, CommandRegistry& registry) {
  auto o = std::make_shared<PartOptions>();
  auto* sub = app.add_subcommand("info", "Load an STL and print a summary (facets, bounds, closed)");
  sub->add_option("stl", o->stl, "STL file")->required();
  add_part_options(sub, *o);
  registry.add(sub, [o] {
    geometry::StlLoadOptions opt;
    opt.units = geometry::parse_length_unit(o->units);
    opt.scale = o->scale;
    const auto r = geometry::load_stl(o->stl, opt);
    std::cout << o->stl << " (" << (r.binary ? "binary" : "ASCII") << " STL";
    if (!r.solid_name.empty()) std::cout << ", '" << r.solid_name << "'";
    std::cout << ")\n" << geometry::summarize(r.mesh, r.dropped_degenerate).to_string();
    // Info shows any file, but says what the jobs would refuse.
    try {
      jobs::check_part_size(r.mesh.bounds(), o->stl, o->max_part_mm);
    } catch (const std::invalid_argument& e) {
      std::cout << "warning: " << e.what() << "; tool paths would be refused\n";
    }
    return 0;
  });
}

}  // namespace cncstream::app
