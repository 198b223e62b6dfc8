// STL bytes (binary or ASCII) -> a mesh, or StlError naming the byte/line.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "cncstream/geometry/stl.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
    const auto r = cncstream::geometry::parse_stl(bytes, "fuzz.stl");
    (void)r.mesh.bounds();
  } catch (const cncstream::geometry::StlError&) {
  }
  return 0;
}
