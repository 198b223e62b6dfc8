// `cncstream info PART.stl`: load an STL and print what a person wants to know.
#include <iostream>
#include <memory>

#include "cncstream/geometry/stl.hpp"
#include "commands.hpp"

namespace cncstream::app {

void register_info(CLI::App& app, CommandRegistry& registry) {
  struct Opts {
    std::string path;
    std::string units = "mm";
    double scale = 1.0;
  };
  auto o = std::make_shared<Opts>();
  auto* sub = app.add_subcommand("info", "Load an STL and print a summary (facets, bounds, closed)");
  sub->add_option("stl", o->path, "STL file")->required();
  sub->add_option("--units", o->units, "Units of the STL: mm, in or m")->check(CLI::IsMember({"mm", "in", "m"}));
  sub->add_option("--scale", o->scale, "Extra scale factor applied after units");
  registry.add(sub, [o] {
    StlLoadOptions opt;
    opt.units = parse_length_unit(o->units);
    opt.scale = o->scale;
    const auto r = load_stl(o->path, opt);
    std::cout << o->path << " (" << (r.binary ? "binary" : "ASCII") << " STL";
    if (!r.solid_name.empty()) std::cout << ", '" << r.solid_name << "'";
    std::cout << ")\n" << summarize(r.mesh, r.dropped_degenerate).to_string();
    return 0;
  });
}

}  // namespace cncstream::app
