#pragma once
// The V-groove part (v_groove.hpp) as a tool path job: finished with one
// ball, rest machined with another, both kept over the block (its surface
// is open: no walls outside it).
#include <memory>
#include <string_view>

#include "cncstream/cam/cutter.hpp"
#include "cncstream/jobs/toolpath_job.hpp"
#include "support/v_groove.hpp"

namespace cncstream::test {

inline jobs::ToolpathParams v_groove_job(std::string_view finish, std::string_view rest) {
  jobs::ToolpathParams p;
  p.part.mesh = std::make_shared<const geometry::Mesh>(v_groove());
  p.part.stl = "v-groove";
  p.cutter = cam::parse_cutter_spec(finish);
  p.rest = cam::parse_cutter_spec(rest);
  p.bounds = cam::XYBounds{3, 3, 37, 17};
  return p;
}

}  // namespace cncstream::test
