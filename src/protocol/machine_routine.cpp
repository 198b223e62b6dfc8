#include "cncstream/protocol/machine_routine.hpp"

#include <fmt/core.h>

#include <cmath>
#include <stdexcept>

namespace cncstream::protocol {

namespace detail_machine_routine {

std::optional<double> number_of(std::string_view text) {
  try {
    std::size_t used = 0;
    const std::string s(text);
    const double v = std::stod(s, &used);
    if (used != s.size() || !std::isfinite(v)) return std::nullopt;
    return v;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

}  // namespace detail_machine_routine

std::string routine_mm(double v) {
  if (std::fabs(v) < 0.0005) v = 0;
  return fmt::format("{:.3f}", v);
}

std::optional<std::pair<std::string, geometry::Vec3>> parse_offset_report(std::string_view line) {
  using detail_machine_routine::number_of;
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.remove_suffix(1);
  if (line.size() < 6 || line.front() != '[' || line.back() != ']') return std::nullopt;
  const auto colon = line.find(':');
  if (colon == std::string_view::npos) return std::nullopt;
  const std::string name(line.substr(1, colon - 1));
  const std::string_view body = line.substr(colon + 1, line.size() - colon - 2);
  if (name == "TLO") {
    const auto z = number_of(body);
    if (!z) return std::nullopt;
    return std::pair{name, geometry::Vec3{0, 0, *z}};
  }
  const bool wcs = name.size() == 3 && name[0] == 'G' && name[1] == '5' && name[2] >= '4' && name[2] <= '9';
  if (!wcs && name != "G92" && name != "G28" && name != "G30") return std::nullopt;
  const auto c1 = body.find(','), c2 = body.rfind(',');
  if (c1 == std::string_view::npos || c2 == c1) return std::nullopt;
  const auto x = number_of(body.substr(0, c1));
  const auto y = number_of(body.substr(c1 + 1, c2 - c1 - 1));
  const auto z = number_of(body.substr(c2 + 1));
  if (!x || !y || !z) return std::nullopt;
  return std::pair{name, geometry::Vec3{*x, *y, *z}};
}

std::optional<int> parse_active_coordinate_system(std::string_view line) {
  if (line.rfind("[GC:", 0) != 0) return std::nullopt;
  for (int i = 0; i < 6; ++i) {
    const std::string word = fmt::format("G5{}", 4 + i);
    for (std::size_t at = line.find(word); at != std::string_view::npos; at = line.find(word, at + 1)) {
      const std::size_t end = at + word.size();
      // G54, not G54.1; a word on its own.
      if ((end == line.size() || line[end] == ' ' || line[end] == ']') && line[at - 1] != '.') return i;
    }
  }
  return std::nullopt;
}

void MachineRoutine::send(std::string line, bool probe, bool reports) {
  line_out_ = std::move(line);
  wait_ = Wait::Answer;
  expect_probe_ = probe;
  probe_seen_ = false;
  if (probe) probe_.reset();
  expect_reports_ = reports;
  if (reports) {
    offsets_.clear();
    wcs_.reset();
  }
}

void MachineRoutine::wait_idle() {
  wait_ = Wait::Idle;
  idle_reports_ = 0;
}

void MachineRoutine::prompt(std::string text, PromptKind kind, int tool) {
  prompt_ = RoutinePrompt{kind, tool, std::move(text)};
  prompt_out_ = prompt_;
  wait_ = Wait::Confirm;
}

void MachineRoutine::fail(const std::string& why) {
  if (!failure_.empty() || done_) return;
  failure_ = context() + ": " + why;
  wait_ = Wait::None;
  prompt_.reset();
  line_out_.reset();
}

void MachineRoutine::abort(const std::string& why) { fail(why); }

void MachineRoutine::step() {
  while (wait_ == Wait::None && failure_.empty() && !done_) {
    if (pc_ >= ops_.size()) {
      done_ = true;
      return;
    }
    ops_[pc_++]();
  }
}

void MachineRoutine::start() {
  build();
  wait_ = Wait::None;
  step();
}

void MachineRoutine::on_answer(bool ok, int code) {
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

void MachineRoutine::on_message(std::string_view line) {
  if (finished() || wait_ != Wait::Answer) return;
  if (expect_probe_)
    if (const auto p = parse_probe_report(line)) {
      probe_seen_ = true;
      probe_ = *p;
      return;
    }
  if (expect_reports_) {
    if (const auto o = parse_offset_report(line)) offsets_[o->first] = o->second;
    if (const auto w = parse_active_coordinate_system(line)) {
      wcs_ = *w;
      inches_ = line.find("G20") != std::string_view::npos;
    }
  }
}

void MachineRoutine::on_status(const StatusReport& r) {
  if (finished()) return;
  status_ = r;
  pin_active_ = r.pins && r.pins->find('P') != std::string::npos;
  if (r.state == MachineState::Alarm) {
    fail("the machine is in alarm");
    return;
  }
  if (hold_ends_it_ && (r.state == MachineState::Hold || r.state == MachineState::Door)) {
    fail("the machine was held (" + r.state_text + "): stopped; nothing more is sent");
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

void MachineRoutine::confirm() {
  if (finished() || wait_ != Wait::Confirm) return;
  prompt_.reset();
  wait_ = Wait::None;
  step();
}

void MachineRoutine::decline() {
  if (finished() || wait_ != Wait::Confirm) return;
  fail(prompt_ && prompt_->kind == PromptKind::Question ? "the operator did not accept the measured length"
                                                         : "the operator declined");
}

}  // namespace cncstream::protocol
