// The T numbers of a complete job's program: a tool picked from the library
// writes its own number; a cutter given as a spec keeps its place in the
// operations' order, moved past any library number of the same program.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cncstream/cam/cutter.hpp"
#include "cncstream/gcode/job_program.hpp"
#include "cncstream/jobs/toolpath_job.hpp"
#include "support/v_groove_job.hpp"

using namespace cncstream;

namespace {

// Roughing with a flat, rest roughing and finishing with a 6 mm ball, rest
// machining with a 2 mm ball.
jobs::ToolpathParams three_tool_job() {
  jobs::ToolpathParams p = test::v_groove_job("ball:6", "ball:2");
  p.rough = cam::parse_cutter_spec("flat:6");
  p.stock = jobs::StockSpec{};
  p.stepover = 1.0;
  p.step = 0.1;
  return p;
}

std::vector<int> operation_tools(const jobs::ToolpathProgram& r) {
  std::vector<int> t;
  for (const auto& o : r.operations) t.push_back(o.tool);
  return t;
}

// The T words in program order, and the tools the program's comments name (read back as the daemon reads them).
std::vector<int> t_words(const std::string& gcode) {
  std::vector<int> t;
  std::size_t at = 0;
  while ((at = gcode.find("\nT", at)) != std::string::npos) {
    ++at;
    t.push_back(std::stoi(gcode.substr(at + 1)));
  }
  return t;
}

std::vector<int> read_back_tools(const std::string& gcode) {
  std::vector<std::string> lines;
  std::size_t from = 0;
  for (std::size_t nl; (nl = gcode.find('\n', from)) != std::string::npos; from = nl + 1)
    lines.push_back(gcode.substr(from, nl - from));
  std::vector<int> t;
  for (const auto& op : program_operations(lines)) t.push_back(op.tool);
  return t;
}

}  // namespace

TEST(JobToolNumbers, LibraryToolsWriteTheirOwnNumbersASpecKeepsItsPlaceAndNeverTakesOne) {
  // Specs only: the operations' order, as before.
  const jobs::ToolpathProgram specs = jobs::generate_toolpath(three_tool_job());
  std::vector<std::string> names;
  for (const auto& o : specs.operations) names.push_back(o.name);
  ASSERT_EQ(names, (std::vector<std::string>{"roughing", "rest roughing", "finishing", "rest machining"}));
  EXPECT_EQ(operation_tools(specs), (std::vector<int>{1, 2, 2, 3}));
  EXPECT_EQ(t_words(specs.gcode), (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(read_back_tools(specs.gcode), (std::vector<int>{1, 2, 2, 3}));

  // Library tools 5 (roughing) and 3 (finishing): T5 then T3; the rest
  // machining's spec would be the third, 3, which the finishing holds: T4.
  jobs::ToolpathParams p = three_tool_job();
  p.rough_tool_number = 5;
  p.tool_number = 3;
  const jobs::ToolpathProgram lib = jobs::generate_toolpath(p);
  EXPECT_EQ(operation_tools(lib), (std::vector<int>{5, 3, 3, 4}));
  EXPECT_EQ(t_words(lib.gcode), (std::vector<int>{5, 3, 4}));
  EXPECT_EQ(read_back_tools(lib.gcode), (std::vector<int>{5, 3, 3, 4}));
  EXPECT_NE(lib.gcode.find("TOOL CHANGE for rest roughing: mount T3"), std::string::npos);
  // The same paths: only the numbers differ.
  EXPECT_EQ(lib.stats.motion_lines, specs.stats.motion_lines);

  // A spec roughing before library tool 1: its place (1) is taken, it becomes T2.
  p = three_tool_job();
  p.tool_number = 1;
  EXPECT_EQ(operation_tools(jobs::generate_toolpath(p)), (std::vector<int>{2, 1, 1, 3}));
}
