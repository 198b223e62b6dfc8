#pragma once
// The outline: before cutting, trace the program's XY extent at a safe
// height and the operator's feed, so the operator sees that the stock is
// where the program expects it. A pure routine (protocol/machine_routine.hpp)
// the machine session runs outside a job.
//
// By default the trace follows the convex hull of the program's XY positions
// (gcode/program_extent.hpp, the one measure of a program's reach: G53/G28
// targets left out, arcs chorded like the firmware), its near-collinear
// vertices dropped within 0.1 mm: the ground the tool covers, which clamps
// and screws must stay out of. `Box` traces the bounding box instead, the
// edges a rectangular block is compared with.
//
// Spindle off, up to the safe Z first (work coordinates, never below the
// program's own highest Z), then the corners one segment at a time, each
// waited for (idle) before the next is sent: a lost link or a stop leaves at
// most the segment in flight. Back to the first corner at the end.
#include <string>
#include <vector>

#include "cncstream/gcode/program_extent.hpp"
#include "cncstream/protocol/machine_routine.hpp"

namespace cncstream::protocol {

enum class OutlineShape { Hull, Box };

// How far a traced hull may run inside the program's true hull, mm.
inline constexpr double kOutlineHullTolerance = 0.1;

struct OutlineConfig {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // the box, work mm
  OutlineShape shape = OutlineShape::Box;
  std::vector<gcode::XyPoint> path;       // the closed trace's corners, work mm (the box's when empty)
  double safe_z = 5;                      // work Z of the trace
  double feed = 1000;                     // mm/min
};

// From a program's extent; `safe_z` nullopt: the program's highest Z. A hull
// of fewer than 3 corners (a program along a line) traces its box.
// Throws std::invalid_argument naming `what` (the file) when the program
// moves neither X nor Y, the feed is not positive, or the safe Z is below
// the program's highest Z (naming both).
OutlineConfig outline_from_extent(const gcode::ProgramExtent& extent, std::optional<double> safe_z, double feed,
                                  const std::string& what, OutlineShape shape = OutlineShape::Hull);

// The corners the trace visits in order (it closes back to the first).
std::vector<gcode::XyPoint> outline_corners(const OutlineConfig& config);

class OutlineTraceRoutine final : public MachineRoutine {
 public:
  explicit OutlineTraceRoutine(OutlineConfig config);
  const char* name() const override { return "outline"; }
  const OutlineConfig& config() const { return cfg_; }

 private:
  void build() override;
  OutlineConfig cfg_;
};

}  // namespace cncstream::protocol
