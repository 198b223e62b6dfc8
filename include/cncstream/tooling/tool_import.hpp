#pragma once
// Imports of the tool libraries users already have. Each returns the tools
// it understood and, for every entry it could not use, the entry's name and
// why; a malformed file throws std::invalid_argument naming the file and the
// place (line, byte, JSON pointer or SQLite table/row).
//   Fusion 360 tool library (.json)      import_fusion_library
//   FreeCAD tool bit (.fctb)             import_freecad_bit
//   FreeCAD tool library (.fctl)         import_freecad_library (its bits read from files)
//   LinuxCNC tool table (tool.tbl)       import_linuxcnc_table
//   Vectric tool database (.vtdb)        import_vectric_database (SQLite)
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "cncstream/tooling/tool.hpp"
#include "cncstream/tooling/tool_library.hpp"

namespace cncstream::tooling {

struct ImportResult {
  std::string format;                   // "Fusion 360 tool library"
  std::vector<Tool> tools;              // number 0: the file gave none (merge_import numbers it)
  std::vector<std::string> understood;  // a line per tool: its entry, its spec and what came with it
  std::vector<std::string> skipped;     // a line per entry not imported: its name and why
};

ImportResult import_fusion_library(std::string_view text, const std::string& source);
ImportResult import_freecad_bit(std::string_view text, const std::string& source);
// The bits' paths are taken relative to `library_dir`, then to its ../Bit
// folder (FreeCAD's layout).
ImportResult import_freecad_library(std::string_view text, const std::string& source,
                                    const std::filesystem::path& library_dir);
// `inch`: the table is in inches (LinuxCNC tables are in machine units).
ImportResult import_linuxcnc_table(std::string_view text, const std::string& source, bool inch = false);
ImportResult import_vectric_database(const std::filesystem::path& path);

// By the file's extension: .json, .fctb, .fctl, .tbl, .vtdb. Throws for
// another or an unreadable file.
ImportResult import_tool_file(const std::filesystem::path& path, bool inch = false);

// Adds the import's tools to `library`. A tool whose number is taken (or
// that has none) gets the next free number unless `replace`; a name taken by
// another tool gets " (2)", " (3)" ... Returns a line per tool saying where it went.
std::vector<std::string> merge_import(ToolLibrary& library, const ImportResult& import, bool replace);

// The report printed after an import: what was understood and what skipped.
std::string import_report(const ImportResult& r);

}  // namespace cncstream::tooling
