// Throughput of the streaming layers: the GRBL engine fed instant `ok`s (how
// many lines per second the host side can push), status-report parsing,
// program preparation, and a durable journal progress row (fsync per row).
#include <benchmark/benchmark.h>

#include <filesystem>
#include <unistd.h>

#include "cncstream/protocol/grbl_session.hpp"
#include "cncstream/protocol/response.hpp"
#include "cncstream/transport/journal.hpp"

using namespace cncstream::protocol;

namespace {

std::vector<std::string> program_lines(int n) {
  std::vector<std::string> lines;
  lines.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i)
    lines.push_back("G1 X" + std::to_string(i % 300) + ".125 Y" + std::to_string((i * 7) % 200) + ".5 Z-1.25 F1500");
  return lines;
}

const FirmwareProfile& grbl() {
  static const auto p = load_firmware_profile(CNCSTREAM_SOURCE_DIR "/firmware-profiles/grbl-1.1.toml");
  return p;
}

void BM_GrblEngineLinesPerSecond(benchmark::State& st) {
  const auto lines = program_lines(static_cast<int>(st.range(0)));
  const auto prepared = prepare_program(lines, "bench.nc", 80);
  GrblSessionOptions o;
  o.poll_status = false;
  for (auto _ : st) {
    GrblSession s(grbl(), o);
    s.start_job(prepared, JobMode::Run, 0);
    double t = 0;
    while (s.progress().state == JobState::Running) {
      const auto out = s.take_output();
      std::string oks;
      for (char c : out)
        if (c == '\n') oks += "ok\n";
      s.on_bytes(oks, t += 1e-4);
      s.take_events();
    }
    benchmark::DoNotOptimize(s.progress().lines_answered);
  }
  st.SetItemsProcessed(st.iterations() * st.range(0));
}
BENCHMARK(BM_GrblEngineLinesPerSecond)->Arg(10000)->Unit(benchmark::kMillisecond);

void BM_ParseStatusReport(benchmark::State& st) {
  const std::string line = "<Run|MPos:123.456,-78.900,-1.250|Bf:12,87|FS:1500,12000|WCO:10.000,20.000,-5.000|Ov:100,100,100|Pn:Z|A:SF>";
  for (auto _ : st) benchmark::DoNotOptimize(parse_response(line));
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_ParseStatusReport);

void BM_PrepareProgram(benchmark::State& st) {
  const auto lines = program_lines(100000);
  for (auto _ : st) benchmark::DoNotOptimize(prepare_program(lines, "bench.nc", 80));
  st.SetItemsProcessed(st.iterations() * 100000);
}
BENCHMARK(BM_PrepareProgram)->Unit(benchmark::kMillisecond);

void BM_JournalProgressRow(benchmark::State& st) {
  const auto path = std::filesystem::temp_directory_path() / ("bench_journal_" + std::to_string(::getpid()) + ".sqlite");
  {
    cncstream::transport::Journal j(path);
    const auto id = j.begin_job("bench.nc", "0", "grbl-1.1", "pty", "run", 1000);
    cncstream::transport::ProgressRecord p;
    p.job_id = id;
    p.reason = "periodic";
    for (auto _ : st) {
      ++p.lines_ok;
      j.record_progress(p);
    }
  }
  for (const char* ext : {"", "-wal", "-shm"}) std::filesystem::remove(path.string() + ext);
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_JournalProgressRow)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
