#pragma once
// A program larger than the machine can move, refused before its first line
// is sent: its extent on an axis (gcode::program_extent) against that axis's
// travel ($130-$132 of a GRBL-family controller). Wherever the work origin
// is, a program that spans more than the travel cannot run: it would hit a
// soft limit (alarm mid-job) or a hard stop. The usual cause is a unit
// mix-up, so the refusal says which factor (25.4, 1000) would make it fit.
#include <array>
#include <optional>
#include <string>

#include "cncstream/gcode/program_extent.hpp"
#include "cncstream/protocol/grbl_settings.hpp"

namespace cncstream::protocol {

// $130, $131, $132 (mm) when all three are known, finite and positive and
// homing is on ($22 not 0: GRBL's homing searches 1.5 times the travel, so a
// homing machine's travel is set; soft limits, $20, need homing); nullopt
// otherwise (homing off, Marlin, a profile without them): no check.
std::optional<std::array<double, 3>> max_travel_from(const GrblSettings& settings);

// Nothing when the program fits (within 0.001 mm); otherwise the refusal:
// each axis that does not fit with the program's extent, its traced range
// and the travel, then the likely cause: a factor 25.4 or 1000 when the
// program is at least twice the travel and that factor makes it fit.
std::optional<std::string> travel_refusal(const gcode::ProgramExtent& extent, const std::array<double, 3>& travel_mm);

}  // namespace cncstream::protocol
