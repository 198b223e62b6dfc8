#pragma once
// The selection report as files: selection.json, table_4_1.csv,
// slope_bins.csv, optionally nodes.csv, and the PNG maps.
#include <filesystem>
#include <vector>

#include "cncstream/jobs/job_control.hpp"
#include "cncstream/jobs/selection_job.hpp"

namespace cncstream::jobs {

struct SelectionReportOptions {
  bool nodes_csv = false;  // also every CL point's heights, d and choices (about 60 bytes a node)
};

// Writes into `dir` (created). Each file appears whole or not at all, and
// selection.json, the report's index, is written last: a folder holding it
// holds the whole report. Returns the files in the order JSON, CSVs, PNGs.
// Throws Cancelled on a stop request (between files).
std::vector<std::filesystem::path> write_selection_report(const SelectionResult& result, const std::filesystem::path& dir,
                                                          const SelectionReportOptions& options = {},
                                                          const JobControl& control = {});

}  // namespace cncstream::jobs
