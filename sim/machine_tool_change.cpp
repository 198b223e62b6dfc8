// The simulated grblHAL's manual tool change (grblHAL core's tool_change.c,
// state_machine.c, stream.c), as far as a sender sees it:
//
// - `$341` selects the mode: 0 the sender's own change, 1-3 the firmware's
//   touch-off (1, 2 manual with $TPW; 3 a fixed sensor at G59.3), 4 M6 ignored.
// - An M6 to another tool than the last M6 mounted waits for the planner,
//   switches spindle and coolant off and enters the Tool state; the line's
//   `ok` follows. Reading the input stream is suspended: lines sent after the
//   M6 stay in the RX buffer, unread.
// - 0xA3 acknowledges: the lines already buffered are kept aside and new
//   ones are read (grblHAL's secondary input buffer), so the host can jog
//   (`$J=`, the machine goes Jog and back to Tool) and send non-motion
//   G-code (`G10 L20` to zero Z); a motion (G0-G3, G38.x) is error:40.
// - Cycle start ends it (mode 0): the kept lines are read again first, the
//   machine is Idle (or runs what is planned).
//
// Not modelled: modes 1-3's own moves and probing ($TPW, the G59.3 sensor);
// cycle start in them says so and leaves the machine in Tool.
#include <fmt/core.h>

#include <cctype>
#include <stdexcept>

#include "cncsim/machine.hpp"

namespace cncsim {

namespace gc = cncstream::gcode;

Firmware parse_firmware(const std::string& text) {
  if (text == "grbl") return Firmware::Grbl11;
  if (text == "grblhal") return Firmware::GrblHal;
  throw std::invalid_argument("firmware '" + text + "': expected grbl or grblhal");
}

int Machine::tool_change_mode() const {
  return grblhal() ? static_cast<int>(store_.settings.get(341)) : 0;
}

// "T2M6" -> "T2", true; "M60", "M6.1", "M61Q2" stay. The cleaned line has
// no spaces or comments, letters upper case.
bool Machine::take_m6_word(std::string& text) const {
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] != 'M') continue;
    std::size_t j = i + 1;
    while (j < text.size() && text[j] == '0') ++j;
    if (j >= text.size() || text[j] != '6') continue;
    const std::size_t end = j + 1;
    if (end < text.size() && (std::isdigit(static_cast<unsigned char>(text[end])) || text[end] == '.')) continue;
    text.erase(i, end - i);
    return true;
  }
  return false;
}

void Machine::enter_tool_change() {
  // grblHAL's tool_change(): spindle and coolant off, then the Tool state.
  parser_.modal.spindle = gc::SpindleState::Off;
  parser_.modal.flood = parser_.modal.mist = false;
  tool_change_ = true;
  tool_read_suspended_ = true;
  state_ = MachineState::Tool;
  ovr_counter_ = 0;
}

void Machine::acknowledge_tool_change() {
  if (!tool_change_ || !tool_read_suspended_) return;
  // The program's lines that followed the M6 wait aside until cycle start.
  tool_backup_.insert(tool_backup_.end(), rx_.begin(), rx_.end());
  rx_.clear();
  tool_read_suspended_ = false;
  if (steps_.empty()) pump();
}

bool Machine::finish_tool_change() {
  const int mode = tool_change_mode();
  if (mode >= 1 && mode <= 3) {
    emit(fmt::format("[MSG:cncsim: the touch-off of tool-change mode $341={} is not simulated; use $341=0]", mode));
    return false;
  }
  // Cycle start: the kept lines first, then whatever arrived since.
  rx_.insert(rx_.begin(), tool_backup_.begin(), tool_backup_.end());
  tool_backup_.clear();
  tool_change_ = false;
  tool_read_suspended_ = false;
  current_tool_ = parser_.tool;
  state_ = queue_.empty() ? MachineState::Idle : MachineState::Run;
  return true;
}

void Machine::reset_tool_change() {
  // A reset during the change: the tool before it stays the current one.
  tool_change_ = false;
  tool_read_suspended_ = false;
  tool_backup_.clear();
  if (state_ == MachineState::Tool) state_ = MachineState::Idle;
}

}  // namespace cncsim
