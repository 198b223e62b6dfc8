// Controller output -> GRBL's answer, status, settings and `$I` parsers, and
// the GRBL engine itself (bytes in, with a job and a jog running).
#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/protocol/grbl_session.hpp"
#include "cncstream/protocol/grbl_settings.hpp"
#include "cncstream/protocol/response.hpp"
#include "cncstream/protocol/status_report.hpp"

using namespace cncstream::protocol;

namespace {
const FirmwareProfile& grbl() {
  static const FirmwareProfile p = load_firmware_profile(CNCSTREAM_SOURCE_DIR "/firmware-profiles/grbl-1.1.toml");
  return p;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  std::size_t start = 0;
  while (start <= bytes.size()) {
    const std::size_t end = std::min(bytes.find('\n', start), bytes.size());
    const std::string_view line = bytes.substr(start, end - start);
    const Response r = parse_response(line);
    if (r.kind == ResponseKind::Options) (void)parse_build_options(r.body);
    (void)parse_status_report(line);
    (void)parse_setting_line(line);
    start = end + 1;
  }
  GrblSession s(grbl());
  std::vector<std::string> lines = {"G21 G90", "G1 X1 F100", "G1 Y1", "M5"};
  s.start_job(prepare_program(lines, "fuzz.nc", grbl().line_length_limit), JobMode::Run, 0);
  // Feed the bytes in two pieces at two times, then let time pass.
  s.on_bytes(bytes.substr(0, size / 2), 0.1);
  s.tick(0.3);
  s.on_bytes(bytes.substr(size / 2), 0.5);
  s.tick(5);
  (void)s.take_output();
  (void)s.take_events();
  return 0;
}
