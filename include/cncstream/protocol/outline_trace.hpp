#pragma once
// The outline: before cutting, trace the program's XY extent at a safe
// height and the operator's feed, so the operator sees that the stock is
// where the program expects it. A pure routine (protocol/machine_routine.hpp)
// the machine session runs outside a job.
//
// The extent is the program's XY bounding box (gcode/program_extent.hpp, the
// one measure of a program's reach: G53/G28 targets left out, arcs chorded
// like the firmware). A box, not the hull: the stock it is checked against is
// a rectangular block, whose edges the operator compares with the box's; a
// hull inside the box would pass a stock that a box trace shows too small.
//
// Spindle off, up to the safe Z first (work coordinates, never below the
// program's own highest Z), then the corners one segment at a time, each
// waited for (idle) before the next is sent: a lost link or a stop leaves at
// most the segment in flight. Back to the first corner at the end.
#include <string>

#include "cncstream/gcode/program_extent.hpp"
#include "cncstream/protocol/machine_routine.hpp"

namespace cncstream::protocol {

struct OutlineConfig {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // the box, work mm
  double safe_z = 5;                      // work Z of the trace
  double feed = 1000;                     // mm/min
};

// From a program's extent; `safe_z` nullopt: the program's highest Z.
// Throws std::invalid_argument naming `what` (the file) when the program
// moves neither X nor Y, the feed is not positive, or the safe Z is below
// the program's highest Z (naming both).
OutlineConfig outline_from_extent(const gcode::ProgramExtent& extent, std::optional<double> safe_z, double feed,
                                  const std::string& what);

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
