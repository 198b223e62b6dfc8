// cncstreamd's configuration: a TOML file -> DaemonConfig, or
// std::invalid_argument naming the file, line and key; and the command
// line's --listen and --machine texts.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <string_view>

#include "cncstream/daemon/config.hpp"

using namespace cncstream::daemon;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const DaemonConfig c = parse_config(text, "fuzz.toml");
    validate(c);  // what parse_config returns is valid
  } catch (const std::invalid_argument& e) {
    if (std::string_view(e.what()).rfind("fuzz.toml", 0) != 0) std::abort();  // names the file
  }
  const std::string line(text.substr(0, text.find('\n')));
  try {
    DaemonConfig c;
    apply_listen(c, line);
  } catch (const std::invalid_argument&) {
  }
  try {
    (void)parse_machine_option(line);
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
