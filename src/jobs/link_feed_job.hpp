#pragma once
// The generated program over the link it will stream on: F lowered where a
// stretch cannot arrive in time, and per operation what the wire allows.
#include "cncstream/gcode/stream_link.hpp"
#include "cncstream/jobs/toolpath_job.hpp"

namespace cncstream::jobs {

void limit_feed_to_link(ToolpathProgram& r, const gcode::StreamLink& link);

}  // namespace cncstream::jobs
