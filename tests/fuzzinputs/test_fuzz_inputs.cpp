// Every fuzz target (tests/fuzz/targets) run in the ordinary test builds —
// the ASan+UBSan one included — over its saved regression inputs and seeds,
// so a fixed crash stays fixed without clang or libFuzzer. The fuzzing itself
// is tools/fuzz.sh. The daemon's targets need the daemon's library: they are
// run by tests/daemon/test_fuzz_inputs_daemon.cpp.
#include "fuzz/replay_inputs.hpp"

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
#define LLVMFuzzerTestOneInput fuzz_pendant_report_one
#include "fuzz/targets/fuzz_pendant_report.cpp"
#undef LLVMFuzzerTestOneInput

using fuzz_replay::run_inputs;

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
TEST(FuzzInputs, PendantReport) { EXPECT_GE(run_inputs("fuzz_pendant_report", fuzz_pendant_report_one), 2u); }
