#pragma once
// Shared by the imports: a tool read from a file is checked (number 0
// allowed: merge_import numbers it), then listed as understood, or its entry
// skipped with why.
#include <fmt/format.h>

#include <stdexcept>
#include <string>

#include "cncstream/tooling/tool_import.hpp"

namespace cncstream::tooling::detail_import_common {

// "<entry> -> <spec> <n> flutes[, T<n>]<extra>"
inline void accept_tool(ImportResult& r, Tool t, const std::string& entry, const std::string& extra) {
  try {
    Tool checked = t;
    if (checked.number == 0) checked.number = 1;
    check_tool(checked);
  } catch (const std::invalid_argument& e) {
    r.skipped.push_back(fmt::format("{}: {}", entry, e.what()));
    return;
  }
  std::string line = fmt::format("{} -> {} {} flutes", entry, t.geometry.spec(), t.flutes);
  if (t.number) line += fmt::format(", T{}", t.number);
  line += extra;
  r.understood.push_back(std::move(line));
  r.tools.push_back(std::move(t));
}

}  // namespace cncstream::tooling::detail_import_common
