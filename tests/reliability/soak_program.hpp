#pragma once
// The soak's program: every line carries its own number (N1..Nn), so the
// simulator can say which lines ran and how often. Mostly short cutting
// moves in a 100 x 100 mm field, with arcs, rapids, coolant and spindle
// changes (buffer syncs), dwells and comments mixed in, from a fixed seed.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

namespace reliability {

inline std::vector<std::string> soak_program(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> step(-1.5, 1.5);
  std::vector<std::string> out;
  out.reserve(n);
  double x = 50, y = 50;
  char buf[96];
  auto add = [&](const char* fmt, auto... v) {
    std::snprintf(buf, sizeof buf, fmt, out.size() + 1, v...);
    out.emplace_back(buf);
  };
  add("N%zuG21G90G94G17F2400");
  add("N%zuM3S12000");
  add("N%zuG0Z5");
  add("N%zuG0X50Y50");
  add("N%zuG1Z-1F600");
  while (out.size() < n) {
    const std::size_t k = out.size() + 1;
    if (k % 997 == 0) {
      add("N%zuM%d", k % 2 ? 8 : 9);
    } else if (k % 1499 == 0) {
      add("N%zuS%dM3", 9000 + static_cast<int>(k % 7) * 1000);
    } else if (k % 2003 == 0) {
      add("N%zuG4P0.01");
    } else if (k % 509 == 0) {
      // A rapid hop: up, across, down.
      x = std::round((10 + std::fmod(x + 37, 80)) * 1000) / 1000;
      add("N%zuG0Z2");
      if (out.size() < n) add("N%zuG0X%.3fY%.3f", x, y);
      if (out.size() < n) add("N%zuG1Z-1F600");
      if (out.size() < n) add("N%zuF2400");
    } else if (k % 97 == 0) {
      // A half circle of radius 2 around a centre 2 mm to +X (several planner blocks).
      const double cx = x + 2;
      const int dir = k % 2 ? 2 : 3;
      x = cx + 2;
      add("N%zuG%dX%.3fY%.3fI2J0", dir, x, y);
    } else {
      // Rounded as printed, so the arcs' centres are exact.
      x = std::round(std::clamp(x + step(rng), 5.0, 95.0) * 1000) / 1000;
      y = std::round(std::clamp(y + step(rng), 5.0, 95.0) * 1000) / 1000;
      if (k % 211 == 0) add("N%zuG1X%.3fY%.3f(k)", x, y);
      else add("N%zuG1X%.3fY%.3f", x, y);
    }
  }
  return out;
}

}  // namespace reliability
