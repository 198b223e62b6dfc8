#pragma once
// Runs a fuzz target (tests/fuzz/targets) over its saved regression inputs
// and checked-in seeds in the ordinary test builds, so a fixed crash stays
// fixed without clang or libFuzzer (the ASan+UBSan build included).
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace fuzz_replay {

using Target = int (*)(const std::uint8_t*, std::size_t);

// The number of inputs run.
inline std::size_t run_inputs(const std::string& name, Target target) {
  namespace fs = std::filesystem;
  std::size_t n = 0;
  for (const char* kind : {"regressions", "corpus"}) {
    const fs::path dir = fs::path(CNCSTREAM_SOURCE_DIR) / "tests/fuzz" / kind / name;
    if (!fs::is_directory(dir)) continue;
    for (const auto& e : fs::directory_iterator(dir)) {
      std::ifstream in(e.path(), std::ios::binary);
      const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      SCOPED_TRACE(e.path().string());
      EXPECT_EQ(target(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()), 0);
      ++n;
    }
  }
  return n;
}

}  // namespace fuzz_replay
