#include "cncstream/pendant/whb04b_report.hpp"

#include <fmt/core.h>

namespace cncstream::pendant {

namespace {

std::string byte_error(int index, const char* what, std::uint8_t value, const char* expected) {
  return fmt::format("byte {} ({}) is 0x{:02x}: expected {}", index, what, value, expected);
}

std::optional<Key> key_from(std::uint8_t b) {
  if (b <= 0x10) return static_cast<Key>(b);
  return std::nullopt;
}

std::optional<FeedKnob> knob_from(std::uint8_t b) {
  switch (b) {
    case 0x00: case 0x0D: case 0x0E: case 0x0F: case 0x10: case 0x1A: case 0x1B: case 0x1C:
      return static_cast<FeedKnob>(b);
    case 0x9B: return FeedKnob::Lead;  // the Lead position of some units
    default: return std::nullopt;
  }
}

std::optional<AxisKnob> axis_from(std::uint8_t b) {
  if (b == 0x00 || b == 0x06 || (b >= 0x11 && b <= 0x16)) return static_cast<AxisKnob>(b);
  return std::nullopt;
}

}  // namespace

const char* to_string(Key k) {
  switch (k) {
    case Key::None: return "none";
    case Key::Reset: return "Reset";
    case Key::Stop: return "Stop";
    case Key::StartPause: return "Start/Pause";
    case Key::FeedPlus: return "Feed+";
    case Key::FeedMinus: return "Feed-";
    case Key::SpindlePlus: return "Spindle+";
    case Key::SpindleMinus: return "Spindle-";
    case Key::MachineHome: return "M-Home";
    case Key::SafeZ: return "Safe-Z";
    case Key::WorkHome: return "W-Home";
    case Key::SpindleOnOff: return "S-On/Off";
    case Key::Fn: return "Fn";
    case Key::ProbeZ: return "Probe-Z";
    case Key::Continuous: return "MPG (continuous)";
    case Key::Step: return "Step";
    case Key::Macro10: return "Macro-10";
  }
  return "?";
}

int fn_macro_number(Key k) {
  switch (k) {
    case Key::FeedPlus: return 1;
    case Key::FeedMinus: return 2;
    case Key::SpindlePlus: return 3;
    case Key::SpindleMinus: return 4;
    case Key::MachineHome: return 5;
    case Key::SafeZ: return 6;
    case Key::WorkHome: return 7;
    case Key::SpindleOnOff: return 8;
    case Key::ProbeZ: return 9;
    case Key::Reset: return 11;
    case Key::Stop: return 12;
    case Key::StartPause: return 13;
    case Key::Macro10: return 14;
    case Key::Continuous: return 15;
    case Key::Step: return 16;
    case Key::None:
    case Key::Fn: return 0;
  }
  return 0;
}

const char* to_string(FeedKnob k) {
  switch (k) {
    case FeedKnob::Unknown: return "unknown";
    case FeedKnob::Step0001: return "0.001/2%";
    case FeedKnob::Step001: return "0.01/5%";
    case FeedKnob::Step01: return "0.1/10%";
    case FeedKnob::Step1: return "1/30%";
    case FeedKnob::Percent60: return "60%";
    case FeedKnob::Percent100: return "100%";
    case FeedKnob::Lead: return "Lead";
  }
  return "?";
}

std::optional<double> knob_step_mm(FeedKnob k) {
  switch (k) {
    case FeedKnob::Step0001: return 0.001;
    case FeedKnob::Step001: return 0.01;
    case FeedKnob::Step01: return 0.1;
    case FeedKnob::Step1: return 1.0;
    default: return std::nullopt;
  }
}

std::optional<int> knob_percent(FeedKnob k) {
  switch (k) {
    case FeedKnob::Step0001: return 2;
    case FeedKnob::Step001: return 5;
    case FeedKnob::Step01: return 10;
    case FeedKnob::Step1: return 30;
    case FeedKnob::Percent60: return 60;
    case FeedKnob::Percent100: return 100;
    default: return std::nullopt;
  }
}

const char* to_string(AxisKnob a) {
  switch (a) {
    case AxisKnob::Unknown: return "unknown";
    case AxisKnob::Off: return "off";
    case AxisKnob::X: return "X";
    case AxisKnob::Y: return "Y";
    case AxisKnob::Z: return "Z";
    case AxisKnob::A: return "A";
    case AxisKnob::B: return "B";
    case AxisKnob::C: return "C";
  }
  return "?";
}

std::optional<int> axis_index(AxisKnob a) {
  switch (a) {
    case AxisKnob::X: return 0;
    case AxisKnob::Y: return 1;
    case AxisKnob::Z: return 2;
    default: return std::nullopt;
  }
}

const char* to_string(PendantEventKind k) {
  switch (k) {
    case PendantEventKind::KeyPressed: return "key pressed";
    case PendantEventKind::KeyReleased: return "key released";
    case PendantEventKind::AxisChanged: return "axis changed";
    case PendantEventKind::KnobChanged: return "knob changed";
    case PendantEventKind::Wheel: return "wheel";
    case PendantEventKind::Sleep: return "sleep";
    case PendantEventKind::Wake: return "wake";
  }
  return "?";
}

std::string hex_bytes(const std::uint8_t* data, std::size_t size) {
  std::string out;
  for (std::size_t i = 0; i < size; ++i) {
    if (i) out.push_back(' ');
    out += fmt::format("{:02x}", data[i]);
  }
  return out;
}

std::optional<PendantReport> decode_report(const InputReport& b, std::string* error) {
  auto fail = [&](std::string why) -> std::optional<PendantReport> {
    if (error) *error = std::move(why);
    return std::nullopt;
  };
  PendantReport r;
  const bool payload_zero = b[2] == 0 && b[3] == 0 && b[4] == 0 && b[5] == 0 && b[6] == 0;
  // The going-to-sleep report: LinuxCNC saw it as 04 ?? 00 00 00 00 00 ??;
  // some receivers send eight zero bytes instead.
  if (payload_zero && (b[0] == 0x04 || (b[0] == 0 && b[1] == 0 && b[7] == 0))) {
    r.kind = ReportKind::Idle;
    return r;
  }
  if (b[0] != 0x04) return fail(byte_error(0, "report id", b[0], "0x04"));
  if (b[2] == 0xFF && b[3] == 0xFF && b[4] == 0xFF && b[5] == 0xFF && b[6] == 0x81) {
    r.kind = ReportKind::Sleeping;
    return r;
  }
  const auto k1 = key_from(b[2]);
  if (!k1) return fail(byte_error(2, "key 1", b[2], "a key code 0x00-0x10"));
  const auto k2 = key_from(b[3]);
  if (!k2) return fail(byte_error(3, "key 2", b[3], "a key code 0x00-0x10"));
  const auto knob = knob_from(b[4]);
  if (!knob) return fail(byte_error(4, "feed knob", b[4], "0x0d-0x10, 0x1a-0x1c or 0x9b"));
  const auto axis = axis_from(b[5]);
  if (!axis) return fail(byte_error(5, "axis knob", b[5], "0x06 (off) or 0x11-0x16 (X-C)"));
  r.key1 = *k1;
  r.key2 = *k2;
  r.fn = r.key1 == Key::Fn || r.key2 == Key::Fn;
  r.feed_knob = *knob;
  r.axis = *axis;
  r.wheel = b[6] < 0x80 ? int{b[6]} : int{b[6]} - 0x100;  // two's complement int8
  return r;
}

std::vector<PendantEvent> PendantInputTracker::update(const PendantReport& r) {
  std::vector<PendantEvent> out;
  if (r.kind != ReportKind::Input) {
    if (!sleeping_) {
      sleeping_ = true;
      held_ = {Key::None, Key::None};  // asleep, nothing is held
      PendantEvent e;
      e.kind = PendantEventKind::Sleep;
      out.push_back(e);
    }
    return out;
  }
  if (sleeping_) {
    sleeping_ = false;
    PendantEvent e;
    e.kind = PendantEventKind::Wake;
    out.push_back(e);
  }
  const std::array<Key, 2> now{r.key1, r.key2};
  auto in = [](const std::array<Key, 2>& set, Key k) { return set[0] == k || set[1] == k; };
  for (Key k : held_)
    if (k != Key::None && !in(now, k)) {
      PendantEvent e;
      e.kind = PendantEventKind::KeyReleased;
      e.key = k;
      out.push_back(e);
    }
  // The knobs before the keys: a key's meaning may depend on them (macro 10
  // zeroes the selected axis), and the pendant reports all in one go.
  if (r.axis != axis_ && r.axis != AxisKnob::Unknown) {
    axis_ = r.axis;
    PendantEvent e;
    e.kind = PendantEventKind::AxisChanged;
    e.axis = r.axis;
    out.push_back(e);
  }
  if (r.feed_knob != knob_ && r.feed_knob != FeedKnob::Unknown) {
    knob_ = r.feed_knob;
    PendantEvent e;
    e.kind = PendantEventKind::KnobChanged;
    e.knob = r.feed_knob;
    out.push_back(e);
  }
  for (Key k : now)
    if (k != Key::None && !in(held_, k)) {
      PendantEvent e;
      e.kind = PendantEventKind::KeyPressed;
      e.key = k;
      e.fn = k != Key::Fn && r.fn;
      out.push_back(e);
    }
  held_ = now;
  if (r.wheel != 0) {
    PendantEvent e;
    e.kind = PendantEventKind::Wheel;
    e.detents = r.wheel;
    e.axis = axis_;
    e.knob = knob_;
    out.push_back(e);
  }
  return out;
}

}  // namespace cncstream::pendant
