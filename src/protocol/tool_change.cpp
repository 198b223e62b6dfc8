#include "cncstream/protocol/tool_change.hpp"

#include <fmt/core.h>

#include <cmath>
#include <stdexcept>

namespace cncstream::protocol {

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
    : cfg_(config), req_(std::move(request)), reference_(reference), mounted_(req_.from_tool) {
  // Inside a job a hold is the job's pause: the routine goes on at cycle start.
  set_hold_ends_it(!req_.in_job);
}

const char* ToolChangeRoutine::name() const {
  switch (req_.kind) {
    case ToolRoutineKind::Change: return "tool change";
    case ToolRoutineKind::MeasureReference: return "tool-length measurement";
    case ToolRoutineKind::CheckLength: return "tool-length check";
  }
  return "tool change";
}

std::string ToolChangeRoutine::context() const {
  return req_.in_job ? fmt::format("tool change at line {}", req_.line) : std::string(name());
}

int ToolChangeRoutine::wcs_index() const { return req_.in_job ? req_.modal.modal.coord_select : wcs_.value_or(0); }

std::optional<double> ToolChangeRoutine::active_offset_z() const {
  const auto it = offsets_.find(fmt::format("G5{}", 4 + wcs_index()));
  if (it == offsets_.end()) return std::nullopt;
  return it->second.z;
}

// Spindle and coolant off, millimetres, up to the safe Z. Outside a job the
// active work offset is read first ($G): no program says which it is.
void ToolChangeRoutine::add_prelude() {
  add([this] { wait_idle(); });
  if (!req_.in_job) {
    add([this] { send("$G", false, true); });
    add([this] {
      if (!wcs_) fail("$G did not report the active work offset (G54..G59)");
    });
  }
  add([this] { send("M5"); });
  add([this] { send("M9"); });
  add([this] { send("G21"); });
  add([this] { send("G53 G0 Z" + routine_mm(cfg_.safe_z)); });
}

void ToolChangeRoutine::add_measure(double* trigger_out) {
  const bool sensor = cfg_.method == ToolChangeMethod::Sensor;
  // Over the plate (work XY: it lies on the work) or the sensor (machine XY), at the safe Z.
  add([this, sensor] {
    send(sensor ? fmt::format("G53 G0 X{} Y{}", routine_mm(cfg_.probe_x), routine_mm(cfg_.probe_y))
                : fmt::format("G90 G0 X{} Y{}", routine_mm(cfg_.probe_x), routine_mm(cfg_.probe_y)));
  });
  add([this] { wait_idle(); });
  // An input already active would alarm at once (ALARM:4): refuse before it.
  add([this] {
    if (pin_active_) fail("the probe input is active before probing (plate touching the bit, clip shorted, sensor stuck): refused");
  });
  // Fast: toward a sensor with G38.3 (no alarm) so a missing contact is ours
  // to report; toward the plate with G38.2. Both bounded by the travel.
  add([this, sensor] {
    send(fmt::format("G91 {} Z-{} F{}", sensor ? "G38.3" : "G38.2", routine_mm(cfg_.probe_travel),
                     routine_mm(cfg_.fast_feed)),
         true);
  });
  add([this] {
    if (!probe_ || !probe_->touched)
      fail(fmt::format("the probe never triggered within {} mm: check the plate or sensor and its wire",
                       routine_mm(cfg_.probe_travel)));
  });
  add([this] { send("G0 Z" + routine_mm(cfg_.retract)); });
  add([this] { wait_idle(); });
  add([this] {
    if (pin_active_) fail("the probe input stays active after backing off: refused");
  });
  add([this] {
    send(fmt::format("G38.2 Z-{} F{}", routine_mm(2 * cfg_.retract), routine_mm(cfg_.slow_feed)), true);
  });
  add([this, trigger_out] {
    if (!probe_ || !probe_->touched) {
      fail("the slow probe did not trigger");
      return;
    }
    *trigger_out = probe_->z;
  });
  add([this] { send("G90"); });
  add([this] { send("G53 G0 Z" + routine_mm(cfg_.safe_z)); });
}

// The tool in the spindle (zeroed by the operator) measured with the work
// offset it was zeroed with: every other tool's offset follows from them.
void ToolChangeRoutine::add_reference_measure() {
  add_measure(&old_trigger_);
  add([this] { wait_idle(); });  // GRBL answers $# with error:8 while moving
  add([this] { send("$#", false, true); });
  add([this] {
    const auto z = active_offset_z();
    if (!z) {
      fail("$# did not report G5" + std::to_string(4 + wcs_index()));
      return;
    }
    reference_ = ToolLengthReference{req_.from_tool, old_trigger_, *z, cfg_.method};
    reference_->measured_tool = req_.from_tool;
    reference_->measured_trigger_z = old_trigger_;
  });
}

void ToolChangeRoutine::add_change(const std::string& what) {
  if (cfg_.method == ToolChangeMethod::Manual) {
    add([this] { wait_idle(); });
    add([this, what] {
      mount_asked_ = true;
      prompt("mount " + what +
                 ", then jog down and zero work Z on the work (the machine is idle, jogging works) and confirm",
             PromptKind::ZeroManually, req_.to_tool);
    });
    add([this] {
      mounted_ = req_.to_tool;
      length_known_ = true;
      reference_.reset();  // a re-zero: lengths measured before no longer apply
      set_summary("the operator zeroed Z with T" + std::to_string(req_.to_tool));
    });
    return;
  }
  // Any tool's trigger and the offset it was zeroed with determine every
  // other tool's offset: the reference is measured once, with the tool in
  // the spindle (zeroed by the operator), and kept.
  if (!reference_ || reference_->method != cfg_.method) add_reference_measure();
  add([this] { wait_idle(); });
  add([this, what] {
    mount_asked_ = true;
    prompt("mount " + what + " (spindle off, at the safe Z) and confirm", PromptKind::MountTool, req_.to_tool);
  });
  add([this] { mounted_ = req_.to_tool; });
  // The operator may have jogged at the prompt: back to the safe Z before any travel.
  add([this] { send("G53 G0 Z" + routine_mm(cfg_.safe_z)); });
  add_measure(&new_trigger_);
  add([this] {
    const double diff = new_trigger_ - reference_->trigger_z;
    if (std::fabs(diff) > cfg_.max_length_change)
      prompt(fmt::format("T{} measured {:+.3f} mm from T{}: more than {} mm; is that the right tool? Confirm to "
                         "apply it, decline to stop {}",
                         req_.to_tool, diff, reference_->tool, routine_mm(cfg_.max_length_change),
                         req_.in_job ? "the job" : "here"),
             PromptKind::Question, req_.to_tool);
  });
  add([this] {
    const double diff = new_trigger_ - reference_->trigger_z;
    offset_written_ = reference_->offset_z + diff;
    send(fmt::format("G10 L2 P{} Z{}", wcs_index() + 1, routine_mm(*offset_written_)));
  });
  add([this] { wait_idle(); });
  add([this] { send("$#", false, true); });
  add([this] {
    const auto read = active_offset_z();
    if (!read || std::fabs(*read - *offset_written_) > 0.0015) {
      fail(fmt::format("the work offset read back ({}) is not the one written ({})",
                       read ? routine_mm(*read) : std::string("none"), routine_mm(*offset_written_)));
      return;
    }
    length_known_ = true;
    reference_->measured_tool = req_.to_tool;
    reference_->measured_trigger_z = new_trigger_;
    set_summary(fmt::format("T{} measured {:+.3f} mm from T{} ({}); work Z offset now {}", req_.to_tool,
                            new_trigger_ - reference_->trigger_z, reference_->tool, to_string(cfg_.method),
                            routine_mm(*offset_written_)));
  });
}

// The broken-bit check: the tool in the spindle measured again; a trigger
// that moved by more than the tolerance means a shorter (broken) or slipped
// bit, or the wrong one: it fails, and its length is unknown.
void ToolChangeRoutine::add_check() {
  add_measure(&new_trigger_);
  add([this] {
    const double recorded = *reference_->measured_trigger_z;
    check_diff_ = new_trigger_ - recorded;
    const double d = *check_diff_;
    if (std::fabs(d) > req_.check_tolerance) {
      fail(fmt::format("T{} is {} mm {} than when it was measured (it triggered at machine Z{} then, Z{} now): "
                       "more than the {} mm allowed; a broken or slipped bit? Its length is unknown: change it",
                       mounted_, routine_mm(std::fabs(d)), d < 0 ? "shorter" : "longer", routine_mm(recorded),
                       routine_mm(new_trigger_), routine_mm(req_.check_tolerance)));
      return;
    }
    length_known_ = true;
    set_summary(fmt::format("T{} is within {} mm of its measured length ({:+.3f} mm; {})", mounted_,
                            routine_mm(req_.check_tolerance), d, to_string(cfg_.method)));
  });
}

void ToolChangeRoutine::add_return() {
  if (!req_.in_job) {
    // Outside a job: it stays at the safe Z; the operator's units come back.
    add([this] {
      if (inches_) send("G20");
    });
    return;
  }
  const gcode::ParserState& m = req_.modal;
  const double k = m.modal.inches ? 1.0 / gcode::kMmPerInch : 1.0;
  const geometry::Vec3 p = m.work_position();  // mm
  add([this] { send("G53 G0 Z" + routine_mm(cfg_.safe_z)); });
  add([this, p] { send(fmt::format("G90 G0 X{} Y{}", routine_mm(p.x), routine_mm(p.y))); });
  if (m.modal.spindle != gcode::SpindleState::Off) {
    const std::string s = fmt::format("{} S{}", m.modal.spindle == gcode::SpindleState::CW ? "M3" : "M4",
                                      fmt::format("{:.0f}", m.spindle_speed));
    add([this, s] { send(s); });
    add([this] { send(fmt::format("G4 P{:.1f}", cfg_.spindle_dwell_s)); });
  }
  if (m.modal.flood) add([this] { send("M8"); });
  if (m.modal.mist) add([this] { send("M7"); });
  add([this, p] { send("G0 Z" + routine_mm(p.z)); });
  // The program's modal state as it left it: units, motion and feed, distance mode.
  if (m.modal.inches) add([this] { send("G20"); });
  const bool linear = m.modal.motion == gcode::MotionMode::Linear;
  std::string motion = linear ? "G1" : "G0";
  if (m.feed_rate > 0 && !m.modal.inverse_time) motion += fmt::format(" F{:.3f}", m.feed_rate * k);
  add([this, motion] { send(motion); });
  if (m.modal.incremental) add([this] { send("G91"); });
}

void ToolChangeRoutine::build() {
  const bool measures = cfg_.method != ToolChangeMethod::Manual;
  switch (req_.kind) {
    case ToolRoutineKind::Change:
      if (req_.to_tool != 0 && req_.to_tool == req_.from_tool) {
        skipped_ = true;
        length_known_ = true;  // what was known of it stays so
        // fmt, not "T" + std::to_string(): GCC 12 at -O3 warns falsely (-Wrestrict) on the latter.
        set_summary(fmt::format("T{} is already in the spindle: nothing to change", req_.to_tool));
        return;
      }
      break;
    case ToolRoutineKind::MeasureReference:
      if (req_.in_job || !measures) {
        fail("the reference is measured with a plate or a sensor, outside a job");
        return;
      }
      break;
    case ToolRoutineKind::CheckLength:
      if (req_.in_job || !measures) {
        fail("a tool's length is checked with a plate or a sensor, outside a job");
        return;
      }
      // Nothing recorded to compare with: refused before anything moves.
      if (!reference_ || !reference_->measured_trigger_z || reference_->measured_tool != req_.from_tool) {
        fail(fmt::format("no measured length of T{} to check against (the reference is measured after a reset, an "
                         "alarm, a homing or a re-zero): measure it first",
                         req_.from_tool));
        return;
      }
      if (reference_->method != cfg_.method) {
        fail(fmt::format("T{} was measured with the {}, not the {}: check it with the same", req_.from_tool,
                         to_string(reference_->method), to_string(cfg_.method)));
        return;
      }
      break;
  }
  add_prelude();
  switch (req_.kind) {
    case ToolRoutineKind::Change: {
      const std::string tool_text = req_.to_tool ? fmt::format("T{}", req_.to_tool) : std::string("the next tool");
      add_change(tool_text + (req_.note.empty() ? std::string() : " (" + req_.note + ")"));
      break;
    }
    case ToolRoutineKind::MeasureReference:
      add_reference_measure();
      add([this] {
        length_known_ = true;
        set_summary(fmt::format("T{} is the reference: it triggered the {} at machine Z{} with work Z offset {}",
                                req_.from_tool, cfg_.method == ToolChangeMethod::Sensor ? "sensor" : "plate",
                                routine_mm(reference_->trigger_z), routine_mm(reference_->offset_z)));
      });
      break;
    case ToolRoutineKind::CheckLength: add_check(); break;
  }
  add_return();
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
  r.note = succeeded() ? summary() : failure();
  return r;
}

}  // namespace cncstream::protocol
