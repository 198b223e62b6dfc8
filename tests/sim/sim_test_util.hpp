#pragma once
// Helpers for simulator tests: split firmware output into lines and a GRBL
// character-counting sender that drives a Machine in virtual time.
#include <deque>
#include <string>
#include <vector>

#include "cncsim/machine.hpp"
#include "cncstream/gcode/line_lexer.hpp"

namespace simtest {

inline std::vector<std::string> lines_of(const std::string& out) {
  std::vector<std::string> v;
  std::string cur;
  for (char c : out) {
    if (c == '\n') {
      if (!cur.empty() && cur.back() == '\r') cur.pop_back();
      v.push_back(cur);
      cur.clear();
    } else {
      cur.push_back(c);
    }
  }
  return v;
}

inline bool is_answer(const std::string& l) { return l == "ok" || l.rfind("error:", 0) == 0; }

// Sends one line and runs until it is answered; returns everything printed.
inline std::string send(cncsim::Machine& m, const std::string& line, double max_seconds = 600) {
  std::string out;
  m.receive(line + "\n");
  for (double t = 0; t < max_seconds; t += 0.05) {
    out += m.take_output();
    for (const auto& l : lines_of(out))
      if (is_answer(l)) return out;
    m.advance(0.05);
  }
  return out + m.take_output();
}

}  // namespace simtest
