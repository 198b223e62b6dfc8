// `cncstream tools list|show|add|import|remove`: the CLI's tool library
// (tooling/tool_library.hpp), a TOML file beside the journal.
#include <fmt/format.h>

#include <iostream>
#include <memory>

#include "cncstream/jobs/output_file.hpp"
#include "cncstream/tooling/feeds_speeds.hpp"
#include "cncstream/tooling/tool_import.hpp"
#include "cncstream/tooling/tool_library.hpp"
#include "commands.hpp"

namespace cncstream::app {

namespace detail_cmd_tools {

std::filesystem::path library_path(const std::string& option) {
  return option.empty() ? tooling::default_tool_library_path() : std::filesystem::path(option);
}

void save(const tooling::ToolLibrary& lib, const std::filesystem::path& path) {
  jobs::write_text_file_atomically(path, tooling::format_tool_library(lib));
}

std::string show_text(const tooling::Tool& t) {
  std::string s = fmt::format("T{} {}\n  shape: {} [{}]\n  flutes: {}\n", t.number, t.name, t.geometry.description(),
                              t.geometry.spec(), t.flutes);
  auto length = [&](const char* what, double v) {
    if (v != 0) s += fmt::format("  {}: {:g} mm\n", what, v);
  };
  length("flute length", t.flute_length);
  length("overall length", t.overall_length);
  length("stick-out", t.stick_out);
  length("shank diameter", t.shank_diameter);
  length("length offset", t.length_offset);
  if (!t.notes.empty()) s += fmt::format("  notes: {}\n", t.notes);
  for (const auto& c : t.cutting) {
    s += fmt::format("  cutting data for {}:", c.material);
    auto v = [&](const char* what, const std::optional<double>& x, const char* unit) {
      if (x) s += fmt::format(" {} {:g}{}", what, *x, unit);
    };
    v("rpm", c.rpm, "");
    v("feed", c.feed, " mm/min");
    v("plunge", c.plunge_feed, " mm/min");
    v("chip load", c.chip_load, " mm");
    v("surface speed", c.surface_speed, " m/min");
    v("stepdown", c.stepdown, " mm");
    v("stepover", c.stepover, " mm");
    s += "\n";
  }
  return s;
}

}  // namespace detail_cmd_tools

void register_tools(CLI::App& app, CommandRegistry& registry) {
  using namespace detail_cmd_tools;
  struct Opts {
    std::string library;
    std::string tool;  // show / remove: number or name
    // add
    int number = 0;
    std::string name, shape;
    int flutes = 2;
    double flute_length = 0, overall_length = 0, stick_out = 0, shank = 0;
    std::string notes;
    bool replace = false;
    // import
    std::string file;
    bool inch = false;
  };
  auto o = std::make_shared<Opts>();
  auto* tools = app.add_subcommand("tools", "The tool library: list, show, add, import and remove tools");
  tools->require_subcommand(1);
  tools->add_option("--library", o->library, "The library file (default: $CNCSTREAM_TOOLS, else tools.toml beside the journal)");

  auto* list = tools->add_subcommand("list", "The library's tools, a line each");
  registry.add(list, [o] {
    const auto path = library_path(o->library);
    const auto lib = tooling::load_tool_library(path);
    std::cout << path.string() << ": " << lib.tools.size() << " tool" << (lib.tools.size() == 1 ? "" : "s") << "\n";
    for (const auto& t : lib.tools) std::cout << "  " << tooling::tool_line(t) << "\n";
    return 0;
  });

  auto* show = tools->add_subcommand("show", "One tool in full, by number or name");
  show->add_option("tool", o->tool, "Number or name")->required();
  registry.add(show, [o] {
    const auto lib = tooling::load_tool_library(library_path(o->library));
    const auto c = tooling::choose_tool(lib, o->tool);
    if (!c.tool) throw std::invalid_argument(fmt::format("'{}' is a spec, not a tool of the library", o->tool));
    std::cout << show_text(*c.tool);
    return 0;
  });

  auto* add = tools->add_subcommand("add", "Add a tool (or, with --replace, replace the tool of its number)");
  add->add_option("--number", o->number, "Its number (default: the smallest free one)")->check(CLI::Range(1, 9999));
  add->add_option("--name", o->name, "Its name, e.g. \"1/8 tapered ball\"")->required();
  add->add_option("--shape", o->shape,
                  "Its shape: flat:D, ball:D, bull:D:r, vbit:ANGLE:D[:TIP_W], taper:TIP_D:ANGLE_PER_SIDE[:TOP_D]")
      ->required();
  add->add_option("--flutes", o->flutes, "Flutes")->check(CLI::Range(1, 12))->capture_default_str();
  add->add_option("--flute-length", o->flute_length, "Flute length, mm")->check(CLI::NonNegativeNumber);
  add->add_option("--overall-length", o->overall_length, "Overall length, mm")->check(CLI::NonNegativeNumber);
  add->add_option("--stick-out", o->stick_out, "Stick-out from the collet, mm")->check(CLI::NonNegativeNumber);
  add->add_option("--shank", o->shank, "Shank diameter, mm")->check(CLI::NonNegativeNumber);
  add->add_option("--notes", o->notes, "A note");
  add->add_flag("--replace", o->replace, "Replace the tool of that number");
  registry.add(add, [o] {
    const auto path = library_path(o->library);
    auto lib = tooling::load_tool_library(path);
    tooling::Tool t;
    t.number = o->number ? o->number : lib.free_number();
    t.name = o->name;
    t.geometry = tooling::parse_tool_spec(o->shape);
    t.flutes = o->flutes;
    t.flute_length = o->flute_length;
    t.overall_length = o->overall_length;
    t.stick_out = o->stick_out;
    t.shank_diameter = o->shank;
    t.notes = o->notes;
    lib.put(t, o->replace);
    save(lib, path);
    std::cout << "added to " << path.string() << ": " << tooling::tool_line(t) << "\n";
    return 0;
  });

  auto* import = tools->add_subcommand(
      "import", "Import a Fusion 360 library (.json), FreeCAD bit (.fctb) or library (.fctl), LinuxCNC tool table "
                "(.tbl) or Vectric tool database (.vtdb)");
  import->add_option("file", o->file, "The file")->required()->check(CLI::ExistingFile);
  import->add_flag("--inch", o->inch, "A LinuxCNC tool table in inches (its machine units)");
  import->add_flag("--replace", o->replace, "Replace the library's tools of the same numbers (default: free numbers)");
  registry.add(import, [o] {
    const auto path = library_path(o->library);
    auto lib = tooling::load_tool_library(path);
    const auto result = tooling::import_tool_file(o->file, o->inch);
    std::cout << tooling::import_report(result);
    const auto lines = tooling::merge_import(lib, result, o->replace);
    save(lib, path);
    std::cout << "into " << path.string() << ":\n";
    for (const auto& l : lines) std::cout << "  " << l << "\n";
    return 0;
  });

  auto* remove = tools->add_subcommand("remove", "Remove a tool, by number or name");
  remove->add_option("tool", o->tool, "Number or name")->required();
  registry.add(remove, [o] {
    const auto path = library_path(o->library);
    auto lib = tooling::load_tool_library(path);
    const auto c = tooling::choose_tool(lib, o->tool);
    if (!c.tool) throw std::invalid_argument(fmt::format("'{}' is a spec, not a tool of the library", o->tool));
    const std::string line = tooling::tool_line(*c.tool);
    lib.remove(c.tool->number);
    save(lib, path);
    std::cout << "removed from " << path.string() << ": " << line << "\n";
    return 0;
  });
}

}  // namespace cncstream::app
