#include "cncstream/tooling/tool_import.hpp"
#include "lower_case.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace cncstream::tooling {

namespace detail_tool_import {

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + ": cannot open for reading");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

using detail_lower_case::lower;

}  // namespace detail_tool_import

ImportResult import_tool_file(const std::filesystem::path& path, bool inch) {
  using namespace detail_tool_import;
  const std::string ext = lower(path.extension().string());
  const std::string source = path.string();
  if (ext == ".vtdb") return import_vectric_database(path);
  if (ext == ".json") return import_fusion_library(read_text(path), source);
  if (ext == ".fctb") return import_freecad_bit(read_text(path), source);
  if (ext == ".fctl") return import_freecad_library(read_text(path), source, path.parent_path());
  if (ext == ".tbl") return import_linuxcnc_table(read_text(path), source, inch);
  throw std::invalid_argument(fmt::format("{}: unknown tool file; expected a Fusion 360 library (.json), a FreeCAD "
                                          "tool bit (.fctb) or library (.fctl), a LinuxCNC tool table (.tbl) or a "
                                          "Vectric tool database (.vtdb)",
                                          source));
}

std::vector<std::string> merge_import(ToolLibrary& library, const ImportResult& import, bool replace) {
  std::vector<std::string> lines;
  for (Tool t : import.tools) {
    std::string how;
    const int wanted = t.number;
    if (t.number == 0 || (!replace && library.by_number(t.number))) {
      t.number = library.free_number();
      how = wanted ? fmt::format(" (T{} is taken by '{}')", wanted, library.by_number(wanted)->name)
                   : std::string(" (the file gave no number)");
    }
    // A name another tool has: numbered.
    const std::string base = t.name;
    auto taken = [&](const std::string& name) {
      const std::string l = detail_tool_import::lower(name);
      return std::any_of(library.tools.begin(), library.tools.end(), [&](const Tool& o) {
        return o.number != t.number && detail_tool_import::lower(o.name) == l;
      });
    };
    for (int n = 2; taken(t.name); ++n) t.name = fmt::format("{} ({})", base, n);
    const bool replacing = library.by_number(t.number) != nullptr;
    library.put(t, true);
    lines.push_back(fmt::format("T{} '{}' {}{}{}", t.number, t.name, t.geometry.spec(),
                                replacing ? " replaces the tool of that number" : "", how));
  }
  return lines;
}

std::string import_report(const ImportResult& r) {
  std::string o = fmt::format("{}: {} tool{} understood, {} entr{} skipped\n", r.format, r.understood.size(),
                              r.understood.size() == 1 ? "" : "s", r.skipped.size(), r.skipped.size() == 1 ? "y" : "ies");
  for (const auto& u : r.understood) o += fmt::format("  understood: {}\n", u);
  for (const auto& s : r.skipped) o += fmt::format("  skipped:    {}\n", s);
  return o;
}

}  // namespace cncstream::tooling
