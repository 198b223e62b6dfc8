// Every fuzz target (tests/fuzz/targets) run in the ordinary test builds —
// the ASan+UBSan one included — over its saved regression inputs and seeds,
// so a fixed crash stays fixed without clang or libFuzzer. The fuzzing itself
// is tools/fuzz.sh.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#define LLVMFuzzerTestOneInput fuzz_stl_one
#include "fuzz/targets/fuzz_stl.cpp"
#undef LLVMFuzzerTestOneInput
#define LLVMFuzzerTestOneInput fuzz_gcode_one
#include "fuzz/targets/fuzz_gcode.cpp"
#undef LLVMFuzzerTestOneInput
#define LLVMFuzzerTestOneInput fuzz_grbl_answers_one
#include "fuzz/targets/fuzz_grbl_answers.cpp"
#undef LLVMFuzzerTestOneInput
#define LLVMFuzzerTestOneInput fuzz_marlin_answers_one
#include "fuzz/targets/fuzz_marlin_answers.cpp"
#undef LLVMFuzzerTestOneInput
#define LLVMFuzzerTestOneInput fuzz_profile_one
#include "fuzz/targets/fuzz_profile.cpp"
#undef LLVMFuzzerTestOneInput
#define LLVMFuzzerTestOneInput fuzz_journal_one
#include "fuzz/targets/fuzz_journal.cpp"
#undef LLVMFuzzerTestOneInput

namespace fs = std::filesystem;

namespace {

using Target = int (*)(const std::uint8_t*, std::size_t);

// The saved regressions and the checked-in seeds of one target.
std::size_t run_inputs(const std::string& name, Target target) {
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

}  // namespace

TEST(FuzzInputs, Stl) { run_inputs("fuzz_stl", fuzz_stl_one); }
TEST(FuzzInputs, Gcode) { EXPECT_GE(run_inputs("fuzz_gcode", fuzz_gcode_one), 4u); }
TEST(FuzzInputs, GrblAnswers) { EXPECT_GE(run_inputs("fuzz_grbl_answers", fuzz_grbl_answers_one), 2u); }
TEST(FuzzInputs, MarlinAnswers) { EXPECT_GE(run_inputs("fuzz_marlin_answers", fuzz_marlin_answers_one), 1u); }
TEST(FuzzInputs, Profile) { EXPECT_GE(run_inputs("fuzz_profile", fuzz_profile_one), 1u); }
TEST(FuzzInputs, Journal) {
  run_inputs("fuzz_journal", fuzz_journal_one);
  const std::string empty;
  EXPECT_EQ(fuzz_journal_one(reinterpret_cast<const std::uint8_t*>(empty.data()), 0), 0);
}
