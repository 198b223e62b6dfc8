#pragma once
// Numbers in the reports' fixed-decimal form ("0.0327"). Private to the jobs layer.
#include <iomanip>
#include <sstream>
#include <string>

namespace cncstream::jobs {

inline std::string fixed_text(double v, int digits = 4) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(digits) << v;
  return o.str();
}

}  // namespace cncstream::jobs
