#pragma once
// A machine's state in MTConnect's words (availability, execution,
// controller mode, program, line, path position, feed, override, alarm),
// derived from a session's snapshot by a pure function: the hub's
// machine_state row, the MQTT state message and the SHDR adapter all say
// the same thing.
#include <array>
#include <optional>
#include <string>

#include "cncstream/session/session_events.hpp"

namespace cncstream::shop {

struct MachineState {
  std::string availability = "UNAVAILABLE";  // AVAILABLE | UNAVAILABLE
  std::string execution = "READY";           // READY, ACTIVE, INTERRUPTED, FEED_HOLD, STOPPED
  std::string controller_mode = "MANUAL";    // AUTOMATIC, MANUAL, MANUAL_DATA_INPUT
  std::string program;                       // the job's file name ("" : none)
  long line = 0;                             // the last line the session knows it sent and was answered
  std::optional<std::array<double, 3>> path_position;  // work position, mm
  std::optional<double> path_feedrate;                 // mm/min
  std::optional<double> feed_override;                 // percent
  std::string alarm;                                   // "" : none; else "ALARM:n text"

  // The fields a change of which is an event (position and feed are live only).
  bool same_event_fields(const MachineState& o) const {
    return availability == o.availability && execution == o.execution && controller_mode == o.controller_mode &&
           program == o.program && alarm == o.alarm;
  }
  std::string to_json() const;  // {"availability": ..., ...}
};

// The mapping (docs/shop.md): no link -> UNAVAILABLE; a job streaming ->
// ACTIVE/AUTOMATIC; Hold -> FEED_HOLD; Door -> INTERRUPTED; Alarm -> STOPPED
// with the alarm; Jog/Home -> ACTIVE/MANUAL; Idle -> READY, AUTOMATIC with a
// job loaded, else MANUAL.
MachineState derive_machine_state(const session::MachineSnapshot& snap, const std::string& program,
                                  const std::string& alarm_text);

}  // namespace cncstream::shop
