// The WHB04B pendant: bytes -> 8-byte input reports -> decode_report -> the
// tracker's key, knob, wheel, sleep and wake events; and the same bytes as a
// replay file (parse_replay), whose every report must decode.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <string>

#include "cncstream/pendant/replay_source.hpp"
#include "cncstream/pendant/whb04b_report.hpp"

using namespace cncstream::pendant;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  PendantInputTracker tracker;
  for (std::size_t at = 0; at + 8 <= size; at += 8) {
    InputReport bytes;
    for (std::size_t i = 0; i < 8; ++i) bytes[i] = data[at + i];
    (void)hex_bytes(bytes.data(), bytes.size());
    std::string why;
    const auto r = decode_report(bytes, &why);
    if (!r) {
      if (why.empty()) std::abort();  // a refusal says why
      continue;
    }
    for (const auto& e : tracker.update(*r)) {
      (void)to_string(e.kind);
      if (e.kind == PendantEventKind::KeyPressed) {
        if (!tracker.key_down(e.key)) std::abort();
        if (e.fn) (void)fn_macro_number(e.key);
      }
      if (e.kind == PendantEventKind::KeyReleased && tracker.key_down(e.key)) std::abort();
      if (e.kind == PendantEventKind::Wheel && (e.detents == 0 || e.detents < -128 || e.detents > 127)) std::abort();
    }
    (void)knob_step_mm(tracker.knob());
    (void)knob_percent(tracker.knob());
    (void)axis_index(tracker.axis());
  }
  std::istringstream text(std::string(reinterpret_cast<const char*>(data), size));
  try {
    for (const auto& e : parse_replay(text, "fuzz.replay"))
      if (e.kind == ReplayKind::Report && !decode_report(e.report)) std::abort();
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
