// The daemon's fuzz targets (tests/fuzz/targets) over their saved regression
// inputs and seeds in the ordinary test builds, so a fixed crash stays fixed
// without clang or libFuzzer. The fuzzing itself is tools/fuzz.sh.
#include "fuzz/replay_inputs.hpp"

#define LLVMFuzzerTestOneInput fuzz_http_request_one
#include "fuzz/targets/fuzz_http_request.cpp"
#undef LLVMFuzzerTestOneInput
#define LLVMFuzzerTestOneInput fuzz_ws_message_one
#include "fuzz/targets/fuzz_ws_message.cpp"
#undef LLVMFuzzerTestOneInput
#define LLVMFuzzerTestOneInput fuzz_job_params_one
#include "fuzz/targets/fuzz_job_params.cpp"
#undef LLVMFuzzerTestOneInput
#define LLVMFuzzerTestOneInput fuzz_daemon_config_one
#include "fuzz/targets/fuzz_daemon_config.cpp"
#undef LLVMFuzzerTestOneInput

using fuzz_replay::run_inputs;

TEST(FuzzInputs, HttpRequest) { EXPECT_GE(run_inputs("fuzz_http_request", fuzz_http_request_one), 10u); }
TEST(FuzzInputs, WsMessage) { EXPECT_GE(run_inputs("fuzz_ws_message", fuzz_ws_message_one), 5u); }
TEST(FuzzInputs, JobParams) { EXPECT_GE(run_inputs("fuzz_job_params", fuzz_job_params_one), 3u); }
TEST(FuzzInputs, DaemonConfig) { EXPECT_GE(run_inputs("fuzz_daemon_config", fuzz_daemon_config_one), 3u); }
