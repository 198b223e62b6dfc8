#pragma once
// The shop's tool library: a TOML file in the data folder (one for the CLI,
// <state>/cncstream/tools.toml; one per daemon, <data_dir>/tools.toml).
//
//   [[tool]]
//   number = 3
//   name = "1/8 tapered ball"
//   shape = "taper:1:5:3.175"        # the spec; the typed fields below are written too
//   flutes = 2
//   flute_length = 19
//   overall_length = 76
//   stick_out = 30
//   [[tool.cutting]]
//   material = "walnut"
//   rpm = 18000
//   chip_load = 0.05
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "cncstream/tooling/tool.hpp"

namespace cncstream::tooling {

struct ToolLibrary {
  std::vector<Tool> tools;  // by number

  const Tool* by_number(int number) const;
  // Adds or, with `replace`, replaces the tool of the same number; throws
  // std::invalid_argument for a number in use (without replace), a name used
  // by another tool, or a tool check_tool refuses.
  void put(const Tool& tool, bool replace);
  // Throws std::invalid_argument when there is no such tool.
  void remove(int number);
  // The smallest number not in use.
  int free_number() const;
};

// What `--tool TEXT` names: a tool of the library by number ("3", "T3") or
// by name (exact, case-insensitive; else the one tool whose name contains
// TEXT), or, when TEXT is a tool spec (flat:6, taper:1:5:3.175), that shape
// with no library tool. Throws std::invalid_argument for an unknown or
// ambiguous name, listing the candidates (or the library's tools).
struct ToolChoice {
  ToolGeometry geometry;
  const Tool* tool = nullptr;  // into the library; null for a spec
  std::string spec() const { return geometry.spec(); }
};
ToolChoice choose_tool(const ToolLibrary& library, std::string_view text);

// TOML text <-> library. parse throws std::invalid_argument
// "<source>:<line>: <what>".
ToolLibrary parse_tool_library(std::string_view text, const std::string& source);
std::string format_tool_library(const ToolLibrary& library);

// A missing file is an empty library; a malformed one throws.
ToolLibrary load_tool_library(const std::filesystem::path& path);
// (Saved by the front ends with jobs::write_text_file_atomically(path,
// format_tool_library(library)): whole or not at all.)

// The CLI's library: $CNCSTREAM_TOOLS if set, else
// $XDG_STATE_HOME/cncstream/tools.toml (~/.local/state/cncstream/tools.toml),
// beside the CLI's journal.
std::filesystem::path default_tool_library_path();

// One line per tool: "T3  1/8 tapered ball  taper:1:5:3.175  2 flutes  stick-out 30 mm".
std::string tool_line(const Tool& t);

}  // namespace cncstream::tooling
