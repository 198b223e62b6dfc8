#include "cncstream/shop/machine_state.hpp"

#include <nlohmann/json.hpp>

namespace cncstream::shop {

std::string MachineState::to_json() const {
  nlohmann::json j = {{"availability", availability}, {"execution", execution}, {"controller_mode", controller_mode},
                      {"program", program}, {"line", line}, {"alarm", alarm}};
  j["path_position"] = path_position ? nlohmann::json(*path_position) : nlohmann::json(nullptr);
  j["path_feedrate"] = path_feedrate ? nlohmann::json(*path_feedrate) : nlohmann::json(nullptr);
  j["feed_override"] = feed_override ? nlohmann::json(*feed_override) : nlohmann::json(nullptr);
  return j.dump();
}

MachineState derive_machine_state(const session::MachineSnapshot& snap, const std::string& program,
                                  const std::string& alarm_text) {
  using protocol::MachineState;
  shop::MachineState s;
  s.program = program;
  s.line = snap.progress.last_answered_line;
  if (snap.link != session::LinkState::Ready) {
    s.availability = "UNAVAILABLE";
    s.execution = "READY";
    s.controller_mode = "MANUAL";
    return s;
  }
  s.availability = "AVAILABLE";
  if (snap.status) {
    const auto& st = *snap.status;
    if (st.wpos) s.path_position = std::array<double, 3>{(*st.wpos)[0], (*st.wpos)[1], (*st.wpos)[2]};
    if (st.feed) s.path_feedrate = *st.feed;
  }
  if (snap.overrides) s.feed_override = (*snap.overrides)[0];
  const auto state = snap.status ? snap.status->state : MachineState::Unknown;
  const bool job = snap.job_active;
  s.controller_mode = job || !program.empty() ? "AUTOMATIC" : "MANUAL";
  if (snap.alarm || state == MachineState::Alarm) {
    s.execution = "STOPPED";
    s.alarm = alarm_text.empty() ? "ALARM" : alarm_text;
    return s;
  }
  switch (state) {
    case MachineState::Hold: s.execution = "FEED_HOLD"; break;
    case MachineState::Door: s.execution = "INTERRUPTED"; break;
    case MachineState::Jog:
    case MachineState::Home:
      s.execution = "ACTIVE";
      if (!job) s.controller_mode = "MANUAL";
      break;
    case MachineState::Run: s.execution = "ACTIVE"; break;
    default:
      // Idle between the last answer and the engine's end of the job is still the job.
      s.execution = job ? "ACTIVE" : "READY";
      break;
  }
  return s;
}

}  // namespace cncstream::shop
