// Controller output -> the Marlin engine (ok, Resend:, busy, errors) with a
// job and a jog.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/protocol/jog.hpp"
#include "cncstream/protocol/marlin_session.hpp"

using namespace cncstream::protocol;

namespace {
const FirmwareProfile& marlin() {
  static const FirmwareProfile p = load_firmware_profile(CNCSTREAM_SOURCE_DIR "/firmware-profiles/marlin.toml");
  return p;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  {
    MarlinSession s(marlin());
    s.tick(0);
    std::vector<std::string> lines = {"G21", "G1 X1 F100", "G1 Y1", "M5"};
    s.start_job(prepare_program(lines, "fuzz.nc", marlin().line_length_limit), JobMode::Run, 0);
    s.on_bytes(bytes, 0.1);
    s.tick(30);
    (void)s.take_output();
    (void)s.take_events();
  }
  MarlinSession j(marlin());
  j.tick(0);
  j.on_bytes("ok\n", 0);
  (void)j.jog_start(JogDirection{{1, 0, 0}}, 600, 0.3, 0);
  j.on_bytes(bytes, 0.1);
  j.jog_release();
  j.tick(1);
  return 0;
}
