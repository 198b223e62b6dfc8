#pragma once
// Jog requests and the words of one jog move. The jog engine (jog_engine.hpp)
// decides the moves; each family engine frames them: GRBL as `$J=G91G21` +
// words, Marlin as `G1` + words between G91 and G90.
#include <array>
#include <string>

namespace cncstream::protocol {

struct JogDirection {
  std::array<double, 3> v{};  // X Y Z components; any scale, normalised by the jog engine
};

// The axis and feed words of a relative move ("X1.000Y-0.500F1000"); axes
// that move less than the controller's 0.001 mm resolution are left out.
std::string move_words(const std::array<double, 3>& delta_mm, double feed_mm_min);

// A GRBL jog line for one relative move: `$J=G91G21X..F..`.
std::string grbl_jog_line(const std::array<double, 3>& delta_mm, double feed_mm_min);

}  // namespace cncstream::protocol
