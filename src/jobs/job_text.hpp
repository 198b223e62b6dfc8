#pragma once
// Small pieces the jobs share: a cutter spec as part of a file name, and a
// stage's wall time. Private to the jobs layer.
#include <chrono>
#include <string>

namespace cncstream::jobs {

// "bull:3.175:0.79" -> "bull_3.175_0.79": no folder separators or colons in file names.
inline std::string safe_name(std::string s) {
  for (char& c : s)
    if (c == ':' || c == '/') c = '_';
  return s;
}

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace cncstream::jobs
