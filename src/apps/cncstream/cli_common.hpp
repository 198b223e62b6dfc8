#pragma once
// Options and loading steps shared by the subcommands that read a part.
#include <CLI/CLI.hpp>

#include <array>
#include <string>

#include "cncstream/cam/cutter.hpp"
#include "cncstream/jobs/job_control.hpp"
#include "cncstream/jobs/part_source.hpp"

namespace cncstream::app {

struct PartOptions {
  std::string stl;
  std::string units = "mm";
  double scale = 1.0;
  double max_part_mm = 3000;  // jobs::kDefaultMaxPartMm
};

void add_part_options(CLI::App* sub, PartOptions& o);
// The jobs' description of the part (the file is read by the job).
jobs::PartSource part_source(const PartOptions& o);

// "X0,Y0,X1,Y1" -> four numbers, with a clear error.
std::array<double, 4> parse_bounds(const std::string& text);

}  // namespace cncstream::app
