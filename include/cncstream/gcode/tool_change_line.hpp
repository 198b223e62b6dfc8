#pragma once
// Where a program changes the tool. GRBL 1.1 has no M6 (error:20) and holds
// on M0 where nobody can jog or probe, so a streamer must recognise the
// change itself and never forward it: M6 (with or without a T word), and an
// M0 that follows a T word (on its own line, or the line just before it,
// comment lines between). A plain M0 is a pause, not a change.
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace cncstream::gcode {

struct ToolChangeLine {
  std::size_t index = 0;  // 0-based line of the M6 / M0
  int tool = 0;           // the tool to mount (the T word in force); 0: the program never says
  std::string note;       // the comments just before it (what to mount, in the program's words)
};

// Every tool change of a program, in order.
std::vector<ToolChangeLine> find_tool_changes(const std::vector<std::string>& lines);

// The tool a program starts with: the first T word before its first tool
// change (0: none).
int first_tool(const std::vector<std::string>& lines);

}  // namespace cncstream::gcode
