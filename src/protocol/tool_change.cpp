#include "cncstream/protocol/tool_change.hpp"

#include <fmt/core.h>

#include <cmath>
#include <stdexcept>

#include "cncstream/protocol/machine_actions.hpp"

namespace cncstream::protocol {

namespace {

// Millimetres on the wire: three decimals, no "-0.000".
std::string tool_change_mm(double v) {
  if (std::fabs(v) < 0.0005) v = 0;
  return fmt::format("{:.3f}", v);
}

// "[G54:1.000,2.000,-3.000]" -> its Z when the name matches.
std::optional<double> offset_line_z(std::string_view line, std::string_view name) {
  if (line.size() < name.size() + 3 || line.front() != '[' || line.substr(1, name.size()) != name ||
      line[name.size() + 1] != ':')
    return std::nullopt;
  const auto c2 = line.rfind(',');
  const auto end = line.find(']');
  if (c2 == std::string_view::npos || end == std::string_view::npos || end < c2) return std::nullopt;
  try {
    std::size_t used = 0;
    const std::string z(line.substr(c2 + 1, end - c2 - 1));
    const double v = std::stod(z, &used);
    if (used != z.size()) return std::nullopt;
    return v;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

}  // namespace

const char* to_string(ToolChangeMethod m) {
  switch (m) {
    case ToolChangeMethod::Plate: return "plate";
    case ToolChangeMethod::Sensor: return "sensor";
    case ToolChangeMethod::Manual: return "manual";
  }
  return "plate";
}

ToolChangeMethod parse_tool_change_method(const std::string& text) {
  if (text == "plate") return ToolChangeMethod::Plate;
  if (text == "sensor") return ToolChangeMethod::Sensor;
  if (text == "manual") return ToolChangeMethod::Manual;
  throw std::invalid_argument("tool-change method '" + text + "': expected plate, sensor or manual");
}

ToolChangeRoutine::ToolChangeRoutine(ToolChangeConfig config, ToolChangeRequest request,
                                     std::optional<ToolLengthReference> reference)
    : cfg_(config), req_(std::move(request)), reference_(reference), mounted_(req_.from_tool) {}

std::string ToolChangeRoutine::wcs_p() const { return std::to_string(req_.modal.modal.coord_select + 1); }

void ToolChangeRoutine::send(std::string line, bool probe, bool offsets) {
  line_out_ = std::move(line);
  wait_ = Wait::Answer;
  expect_probe_ = probe;
  probe_seen_ = false;
  probe_touched_ = false;
  probe_z_.reset();
  expect_offsets_ = offsets;
  if (offsets) offset_read_z_.reset();
}

void ToolChangeRoutine::wait_idle() {
  wait_ = Wait::Idle;
  idle_reports_ = 0;
}

void ToolChangeRoutine::prompt(PromptKind kind, std::string text) {
  ToolChangePrompt p{kind, req_.to_tool, std::move(text)};
  prompt_ = p;
  prompt_out_ = p;
  wait_ = Wait::Confirm;
}

void ToolChangeRoutine::fail(std::string why) {
  if (!failure_.empty() || done_) return;
  failure_ = "tool change at line " + std::to_string(req_.line) + ": " + why;
  wait_ = Wait::None;
  prompt_.reset();
  line_out_.reset();
}

void ToolChangeRoutine::abort(const std::string& why) { fail(why); }

void ToolChangeRoutine::step() {
  while (wait_ == Wait::None && failure_.empty() && !done_) {
    if (pc_ >= ops_.size()) {
      done_ = true;
      return;
    }
    auto& op = ops_[pc_++];
    op.run();
  }
}

void ToolChangeRoutine::add_measure(double* trigger_out) {
  const bool sensor = cfg_.method == ToolChangeMethod::Sensor;
  // Over the plate (work XY: it lies on the work) or the sensor (machine XY), at the safe Z.
  add([this, sensor] {
    send(sensor ? fmt::format("G53 G0 X{} Y{}", tool_change_mm(cfg_.probe_x), tool_change_mm(cfg_.probe_y))
                : fmt::format("G90 G0 X{} Y{}", tool_change_mm(cfg_.probe_x), tool_change_mm(cfg_.probe_y)));
  });
  add([this] { wait_idle(); });
  // An input already active would alarm at once (ALARM:4): refuse before it.
  add([this] {
    if (pin_active_) fail("the probe input is active before probing (plate touching the bit, clip shorted, sensor stuck): refused");
  });
  // Fast: toward a sensor with G38.3 (no alarm) so a missing contact is ours
  // to report; toward the plate with G38.2. Both bounded by the travel.
  add([this, sensor] {
    send(fmt::format("G91 {} Z-{} F{}", sensor ? "G38.3" : "G38.2", tool_change_mm(cfg_.probe_travel),
                     tool_change_mm(cfg_.fast_feed)),
         true);
  });
  add([this] {
    if (!probe_touched_ || !probe_z_)
      fail(fmt::format("the probe never triggered within {} mm: check the plate or sensor and its wire",
                       tool_change_mm(cfg_.probe_travel)));
  });
  add([this] { send("G0 Z" + tool_change_mm(cfg_.retract)); });
  add([this] { wait_idle(); });
  add([this] {
    if (pin_active_) fail("the probe input stays active after backing off: refused");
  });
  add([this] {
    send(fmt::format("G38.2 Z-{} F{}", tool_change_mm(2 * cfg_.retract), tool_change_mm(cfg_.slow_feed)), true);
  });
  add([this, trigger_out] {
    if (!probe_touched_ || !probe_z_) {
      fail("the slow probe did not trigger");
      return;
    }
    *trigger_out = *probe_z_;
  });
  add([this] { send("G90"); });
  add([this] { send("G53 G0 Z" + tool_change_mm(cfg_.safe_z)); });
}

void ToolChangeRoutine::add_return() {
  const gcode::ParserState& m = req_.modal;
  const double k = m.modal.inches ? 1.0 / gcode::kMmPerInch : 1.0;
  const Vec3 p = m.work_position();  // mm
  add([this] { send("G53 G0 Z" + tool_change_mm(cfg_.safe_z)); });
  add([this, p] { send(fmt::format("G90 G0 X{} Y{}", tool_change_mm(p.x), tool_change_mm(p.y))); });
  if (m.modal.spindle != gcode::SpindleState::Off) {
    const std::string s = fmt::format("{} S{}", m.modal.spindle == gcode::SpindleState::CW ? "M3" : "M4",
                                      fmt::format("{:.0f}", m.spindle_speed));
    add([this, s] { send(s); });
    add([this] { send(fmt::format("G4 P{:.1f}", cfg_.spindle_dwell_s)); });
  }
  if (m.modal.flood) add([this] { send("M8"); });
  if (m.modal.mist) add([this] { send("M7"); });
  add([this, p] { send("G0 Z" + tool_change_mm(p.z)); });
  // The program's modal state as it left it: units, motion and feed, distance mode.
  if (m.modal.inches) add([this] { send("G20"); });
  const bool linear = m.modal.motion == gcode::MotionMode::Linear;
  std::string motion = linear ? "G1" : "G0";
  if (m.feed_rate > 0 && !m.modal.inverse_time) motion += fmt::format(" F{:.3f}", m.feed_rate * k);
  add([this, motion] { send(motion); });
  if (m.modal.incremental) add([this] { send("G91"); });
}

void ToolChangeRoutine::start() {
  if (req_.to_tool != 0 && req_.to_tool == req_.from_tool) {
    skipped_ = true;
    length_known_ = true;  // what was known of it stays so
    // fmt, not "T" + std::to_string(): GCC 12 at -O3 warns falsely (-Wrestrict) on the latter.
    summary_ = fmt::format("T{} is already in the spindle: nothing to change", req_.to_tool);
    done_ = true;
    return;
  }
  const std::string tool_text = req_.to_tool ? fmt::format("T{}", req_.to_tool) : std::string("the next tool");
  const std::string what = tool_text + (req_.note.empty() ? std::string() : " (" + req_.note + ")");
  add([this] { wait_idle(); });
  add([this] { send("M5"); });
  add([this] { send("M9"); });
  add([this] { send("G21"); });
  add([this] { send("G53 G0 Z" + tool_change_mm(cfg_.safe_z)); });
  if (cfg_.method == ToolChangeMethod::Manual) {
    add([this] { wait_idle(); });
    add([this, what] {
      mount_asked_ = true;
      prompt(PromptKind::ZeroManually, "mount " + what +
                                           ", then jog down and zero work Z on the work (the machine is idle, jogging "
                                           "works) and confirm");
    });
    add([this] {
      mounted_ = req_.to_tool;
      length_known_ = true;
      reference_.reset();  // a re-zero: lengths measured before no longer apply
      summary_ = "the operator zeroed Z with T" + std::to_string(req_.to_tool);
    });
  } else {
    // Any tool's trigger and the offset it was zeroed with determine every
    // other tool's offset: the reference is measured once, with the tool in
    // the spindle (zeroed by the operator), and kept.
    const bool need_reference = !reference_ || reference_->method != cfg_.method;
    if (need_reference) {
      add_measure(&old_trigger_);
      add([this] { wait_idle(); });  // GRBL answers $# with error:8 while moving
      add([this] { send("$#", false, true); });
      add([this] {
        if (!offset_read_z_) {
          fail("$# did not report G5" + std::to_string(3 + req_.modal.modal.coord_select + 1));
          return;
        }
        reference_ = ToolLengthReference{req_.from_tool, old_trigger_, *offset_read_z_, cfg_.method};
      });
    }
    add([this] { wait_idle(); });
    add([this, what] {
      mount_asked_ = true;
      prompt(PromptKind::MountTool, "mount " + what + " (spindle off, at the safe Z) and confirm");
    });
    add([this] { mounted_ = req_.to_tool; });
    // The operator may have jogged at the prompt: back to the safe Z before any travel.
    add([this] { send("G53 G0 Z" + tool_change_mm(cfg_.safe_z)); });
    add_measure(&new_trigger_);
    add([this] {
      const double diff = new_trigger_ - reference_->trigger_z;
      if (std::fabs(diff) > cfg_.max_length_change)
        prompt(PromptKind::Question,
               fmt::format("T{} measured {:+.3f} mm from T{}: more than {} mm; is that the right tool? Confirm to "
                           "apply it, decline to stop the job",
                           req_.to_tool, diff, reference_->tool, tool_change_mm(cfg_.max_length_change)));
    });
    add([this] {
      const double diff = new_trigger_ - reference_->trigger_z;
      offset_written_ = reference_->offset_z + diff;
      send("G10 L2 P" + wcs_p() + " Z" + tool_change_mm(*offset_written_));
    });
    add([this] { wait_idle(); });
    add([this] { send("$#", false, true); });
    add([this] {
      if (!offset_read_z_ || std::fabs(*offset_read_z_ - *offset_written_) > 0.0015) {
        fail(fmt::format("the work offset read back ({}) is not the one written ({})",
                         offset_read_z_ ? tool_change_mm(*offset_read_z_) : std::string("none"),
                         tool_change_mm(*offset_written_)));
        return;
      }
      length_known_ = true;
      summary_ = fmt::format("T{} measured {:+.3f} mm from T{} ({}); work Z offset now {}", req_.to_tool,
                             new_trigger_ - reference_->trigger_z, reference_->tool, to_string(cfg_.method),
                             tool_change_mm(*offset_written_));
    });
  }
  add_return();
  wait_ = Wait::None;
  step();
}

void ToolChangeRoutine::on_answer(bool ok, int code) {
  if (finished() || wait_ != Wait::Answer) return;
  if (!ok) {
    fail(fmt::format("the controller refused a line of the routine (error:{})", code));
    return;
  }
  if (expect_probe_ && !probe_seen_) {
    fail("a probe was answered without its [PRB:] report");
    return;
  }
  wait_ = Wait::None;
  step();
}

void ToolChangeRoutine::on_message(std::string_view line) {
  if (finished()) return;
  if (expect_probe_ && wait_ == Wait::Answer) {
    if (const auto p = parse_probe_report(line)) {
      probe_seen_ = true;
      probe_touched_ = p->touched;
      probe_z_ = p->z;
      return;
    }
  }
  if (expect_offsets_ && wait_ == Wait::Answer) {
    const std::string name = "G5" + std::to_string(4 + req_.modal.modal.coord_select);
    if (const auto z = offset_line_z(line, name)) offset_read_z_ = *z;
  }
}

void ToolChangeRoutine::on_status(const StatusReport& r) {
  if (finished()) return;
  pin_active_ = r.pins && r.pins->find('P') != std::string::npos;
  if (r.state == MachineState::Alarm) {
    fail("the machine is in alarm");
    return;
  }
  if (wait_ != Wait::Idle) return;
  // Two reports in a row: the first may predate the last move's start.
  idle_reports_ = r.state == MachineState::Idle ? idle_reports_ + 1 : 0;
  if (idle_reports_ >= 2) {
    wait_ = Wait::None;
    step();
  }
}

void ToolChangeRoutine::confirm() {
  if (finished() || wait_ != Wait::Confirm) return;
  prompt_.reset();
  wait_ = Wait::None;
  step();
}

void ToolChangeRoutine::decline() {
  if (finished() || wait_ != Wait::Confirm) return;
  fail(prompt_ && prompt_->kind == PromptKind::Question ? "the operator did not accept the measured length"
                                                         : "the operator declined");
}

ToolChangeRecord ToolChangeRoutine::record() const {
  ToolChangeRecord r;
  r.line = req_.line;
  r.method = cfg_.method;
  r.skipped = skipped_;
  // Once the operator was asked to mount the new tool, it may be in the spindle.
  r.tool = mounted_;
  if (!succeeded() && mount_asked_ && mounted_ == req_.from_tool) r.tool = req_.to_tool;
  r.length_known = succeeded() && length_known_;
  r.offset_z = offset_written_;
  r.note = succeeded() ? summary_ : failure_;
  return r;
}

}  // namespace cncstream::protocol
