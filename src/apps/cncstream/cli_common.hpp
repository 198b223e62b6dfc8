#pragma once
// Options and loading steps shared by the subcommands that read a part.
#include <CLI/CLI.hpp>

#include <chrono>
#include <string>

#include "cncstream/cam/cutter.hpp"
#include "cncstream/geometry/stl.hpp"

namespace cncstream::app {

struct PartOptions {
  std::string stl;
  std::string units = "mm";
  double scale = 1.0;
};

void add_part_options(CLI::App* sub, PartOptions& o);
// Loads the STL; prints nothing. Errors name the file and place.
StlLoadResult load_part(const PartOptions& o);

// "X0,Y0,X1,Y1" -> four numbers, with a clear error.
std::array<double, 4> parse_bounds(const std::string& text);

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace cncstream::app
