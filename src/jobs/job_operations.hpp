#pragma once
// The operations of a tool path job put together (toolpath_job.hpp): the
// finishing's summary, and the program of them all with the tool changes
// between the cutters. Private to the jobs layer.
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cncstream/cam/checkpoint.hpp"
#include "cncstream/cam/stock.hpp"
#include "cncstream/cam/zlevel_roughing.hpp"
#include "cncstream/jobs/toolpath_job.hpp"
#include "rest_stage.hpp"
#include "roughing_stage.hpp"

namespace cncstream::jobs {

// The finishing operation's summary from its program's stats.
OperationSummary finishing_summary(const ToolpathProgram& r, const ToolpathParams& p, const ProgramStats& stats);

// The T number of each cutter of a program, in its order (the cutters that
// follow one another without a tool change given once): a library tool's
// own number; a cutter given as a spec (nullopt) its place among them (1,
// 2, 3), moved up past every library number of the program and every
// number already given, so that no two cutters share a T.
std::vector<int> job_tool_numbers(const std::vector<std::optional<int>>& library_numbers);

// The whole program (roughing, tool change, rest roughing, finishing, tool
// change, rest machining) into r.gcode, r.stats and r.operations; the notes
// into r.notes. Either stage may be missing (null), not both.
void compose_job(ToolpathProgram& r, const ToolpathParams& p, const RoughingStage* rough, const RestStage* rest,
                 MachiningParams mp);

}  // namespace cncstream::jobs
