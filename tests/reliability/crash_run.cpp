#include "crash_run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>
#include <random>
#include <sstream>
#include <thread>

#include "child.hpp"
#include "cncstream/cam/height_field_io.hpp"
#include "cncstream/transport/journal.hpp"
#include "sim/pty_process.hpp"

namespace reliability {

namespace fs = std::filesystem;
using cncstream::transport::Journal;

namespace {

const std::string kBin = CNCSTREAM_BINARY_DIR;
const std::string kDesign = std::string(CNCSTREAM_SOURCE_DIR) + "/examples/plaque.stl";
const char* kTool = "ball:3.175";
const char* kResolution = "0.5";

std::string cncstream_exe() { return kBin + "/cncstream"; }

// Strict: an RX buffer overflow (a streamer that miscounts) ends the simulator and fails the run.
std::vector<std::string> sim_args(const std::string& speed, const fs::path& result) {
  return {"--strict", "--speed", speed, "--design", kDesign, "--tool", kTool, "--resolution", kResolution,
          "--result", result.string()};
}

std::size_t count_lines(const fs::path& p) {
  std::ifstream f(p);
  std::size_t n = 0;
  std::string l;
  while (std::getline(f, l)) ++n;
  return n;
}

// The verify summary the simulator printed at exit.
std::string verify_text(const std::string& err) {
  const auto at = err.find("cncsim verify against");
  return at == std::string::npos ? std::string() : err.substr(err.find('\n', at) + 1);
}

// "final position MPos x,y,z" from the simulator's exit summary.
std::optional<std::string> final_position(const std::string& err) {
  const auto at = err.find("final position MPos ");
  if (at == std::string::npos) return std::nullopt;
  const auto start = at + 19;
  return err.substr(start, err.find(',', err.find(',', err.find(',', start) + 1) + 1) - start);
}

class CrashRun {
 public:
  explicit CrashRun(const CrashOptions& o) : opt_(o), rng_(o.seed * 104729 + 3) {}

  CrashReport run() {
    const auto t0 = std::chrono::steady_clock::now();
    fs::create_directories(opt_.dir);
    env_ = {"XDG_STATE_HOME=" + (opt_.dir / "state").string()};
    program_ = opt_.dir / "corner.nc";
    make_program();
    report_.program_lines = count_lines(program_);
    make_reference();
    if (report_.problems.empty()) crash_and_resume();
    report_.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return report_;
  }

 private:
  void problem(const std::string& p) { report_.problems.push_back(p); }

  // ---- the job and the uninterrupted run -----------------------------------------

  void make_program() {
    if (fs::exists(program_)) return;
    Child c(cncstream_exe(),
            {"toolpath", kDesign, "--tool", kTool, "--stepover", "1.5", "--origin", "model", "--z-zero", "model",
             "--bounds", "0,0,40,30", "--stock", "none", "--strategy", "raster", "-o", program_.string()},
            env_, opt_.dir / "toolpath.log");
    if (!c.wait(120) || c.code() != 0) problem("toolpath failed: " + c.output());
  }

  void make_reference() {
    reference_ = opt_.dir / "reference.f32";
    const fs::path verify_file = opt_.dir / "reference.verify";
    if (fs::exists(reference_) && fs::exists(verify_file)) {
      std::ifstream f(verify_file);
      std::stringstream s;
      s << f.rdbuf();
      report_.reference_verify = s.str();
      return;
    }
    simtest::SimProcess sim(sim_args("max", reference_));
    const fs::path db = opt_.dir / "reference.sqlite";
    fs::remove(db);
    Child c(cncstream_exe(), {program_.string(), sim.slave(), "--journal", db.string(), "--yes"}, env_,
            opt_.dir / "reference.log");
    if (!c.wait(300) || c.code() != 0) return problem("the uninterrupted run failed: " + c.output());
    sim.stop();
    report_.reference_verify = verify_text(sim.stderr_text());
    std::ofstream(verify_file) << report_.reference_verify;
  }

  // ---- the job, killed and resumed ------------------------------------------------------

  void start_sim(const std::vector<std::string>& extra) {
    ++sims_;
    result_ = opt_.dir / ("crash" + std::to_string(sims_) + ".f32");
    auto args = sim_args(opt_.sim_speed, result_);
    args.insert(args.end(), extra.begin(), extra.end());
    sim_ = std::make_unique<simtest::SimProcess>(args);
  }

  // The newest job and its last progress row, as the journal holds them now.
  struct Newest {
    std::int64_t id = 0;
    std::optional<std::string> outcome;
    long last_line = 0;
    std::int64_t total = 0;
    bool has_progress = false;
  };
  Newest newest() {
    Newest n;
    const auto jobs = journal_->jobs(1);
    if (jobs.empty()) return n;
    n.id = jobs[0].id;
    n.outcome = jobs[0].outcome;
    n.total = jobs[0].total_lines;
    if (const auto p = journal_->last_progress(n.id)) {
      n.last_line = static_cast<long>(p->last_line);
      n.has_progress = true;
    }
    return n;
  }

  std::unique_ptr<Child> start_cncstream() {
    ++report_.runs;
    const fs::path log = opt_.dir / ("run" + std::to_string(report_.runs) + ".log");
    std::vector<std::string> args;
    const Newest n = newest();
    if (n.id == 0) {
      args = {program_.string(), sim_->slave()};
    } else {
      args = {"resume", std::to_string(n.id), sim_->slave(), "--dwell", "0"};
    }
    args.insert(args.end(), {"--journal", db_.string(), "--yes"});
    return std::make_unique<Child>(cncstream_exe(), args, env_, log);
  }

  // `cncstream jobs` and `jobs --show` agree with the journal about the newest job.
  void check_listed(KillRecord& k, const char* expected_outcome) {
    const Newest n = newest();
    k.job = n.id;
    k.last_line = n.last_line;
    if (n.id == 0) return;  // killed before the first job row: nothing to list yet
    if (n.outcome.value_or("interrupted") != expected_outcome)
      problem("job " + std::to_string(n.id) + " is journaled '" + n.outcome.value_or("interrupted") + "', expected '" +
              expected_outcome + "'");
    Child list(cncstream_exe(), {"jobs", "--journal", db_.string()}, env_, opt_.dir / "jobs.log");
    list.wait(30);
    const std::string out = list.output();
    std::istringstream lines(out);
    std::string line;
    const std::string id = std::to_string(n.id);
    while (std::getline(lines, line)) {
      std::istringstream w(line);
      std::string first;
      w >> first;
      if (first == id) k.listed = line;
    }
    const std::string fraction = " " + std::to_string(n.last_line) + "/" + std::to_string(n.total) + " ";
    if (k.listed.find(std::string(" ") + expected_outcome + " ") == std::string::npos ||
        k.listed.find(fraction) == std::string::npos)
      problem("`cncstream jobs` lists job " + id + " as '" + k.listed + "', expected " + expected_outcome + " and" +
              fraction);
    Child show(cncstream_exe(), {"jobs", "--journal", db_.string(), "--show", id}, env_, opt_.dir / "show.log");
    show.wait(30);
    const std::string s = show.output();
    if (n.has_progress && s.find("last answered file line " + std::to_string(n.last_line)) == std::string::npos)
      problem("`cncstream jobs --show " + id + "` does not give the last answered line " +
              std::to_string(n.last_line) + ":\n" + s);
    if (std::string(expected_outcome) == "interrupted" && s.find("interrupted (the process died mid-job)") == std::string::npos)
      problem("`cncstream jobs --show " + id + "` does not say the job was interrupted:\n" + s);
  }

  long resumed_after(const std::string& out) {
    const auto at = out.find("continue after line ");
    return at == std::string::npos ? -1 : std::stol(out.substr(at + 20));
  }

  void crash_and_resume() {
    fs::remove_all(opt_.dir / "state");
    db_ = opt_.dir / "crash.sqlite";
    for (const char* ext : {"", "-wal", "-shm"}) fs::remove(db_.string() + ext);
    journal_ = std::make_unique<Journal>(db_);  // created before any writer, read while they run
    start_sim({});
    const int sim_kill_at = opt_.kill_simulator ? opt_.kills / 2 : -1;
    std::uniform_real_distribution<double> line_frac(0.02, 0.98), seconds(0.05, 4.0);
    // The lines to kill at, in order, so the kills spread over the whole job.
    std::vector<long> targets;
    for (int k = 0; k < opt_.kills; ++k) targets.push_back(static_cast<long>(line_frac(rng_) * double(report_.program_lines)));
    std::sort(targets.begin(), targets.end());
    std::unique_ptr<Child> run = start_cncstream();
    for (int k = 0; k < opt_.kills; ++k) {
      KillRecord rec;
      rec.victim = k == sim_kill_at ? "cncsim" : "cncstream";
      const std::int64_t before = newest().id;
      // A third of the moments are times after the start: they land in
      // identification and in a resume's preamble as well as in the cut.
      if (k % 3 == 2 && k != sim_kill_at) {
        const double t = seconds(rng_);
        char buf[48];
        std::snprintf(buf, sizeof buf, "%.2f s after start", t);
        rec.moment = buf;
        run->wait(t);
      } else {
        const long target = targets[static_cast<std::size_t>(k)];
        rec.moment = "line >= " + std::to_string(target);
        const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(120);
        for (;;) {
          const Newest n = newest();
          if ((n.id > before && n.has_progress && n.last_line >= target) || run->exited()) break;
          if (std::chrono::steady_clock::now() > end) {
            problem("no progress to line " + std::to_string(target) + " within 120 s:\n" + run->output());
            return;
          }
          std::this_thread::sleep_for(std::chrono::milliseconds(5));  // polling the journal
        }
      }
      if (run->exited()) {
        // The job completed before this moment came: no more kills.
        rec.moment += " (the job had completed)";
        report_.kills.push_back(rec);
        break;
      }
      if (rec.victim == "cncstream") {
        run->kill9();
        if (newest().outcome.value_or("") == "completed") {
          // It completed the job in the instant before the kill (and was
          // only finishing its report): nothing is left to resume.
          rec.moment += " (the job had just completed)";
          rec.job = newest().id;
          report_.kills.push_back(rec);
          report_.completed = true;
          break;
        }
        check_listed(rec, "interrupted");
      } else {
        kill_simulator(*run, rec);
        if (!report_.problems.empty()) return;
      }
      run = start_cncstream();
      report_.kills.push_back(rec);
      resume_logs_.push_back(report_.runs);
    }
    // The last run goes to the end.
    if (!report_.completed) {
      if (!run->exited() && !run->wait(300)) problem("the last resume did not finish within 300 s");
      const std::string out = run->output();
      report_.completed = run->code() == 0 && out.find("outcome: completed") != std::string::npos;
      if (!report_.completed)
        problem("the last run did not complete the job (exit " + std::to_string(run->code()) + "):\n" + out);
    }
    fill_resumed_after();
    sim_->stop();
    report_.final_verify = verify_text(sim_->stderr_text());
    compare_surfaces();
  }

  // The simulator dies (its port vanishes) mid-job; a fresh one starts from
  // the state the dead one saved: its machined surface and its tool position.
  void kill_simulator(Child& run, KillRecord& rec) {
    sim_->stop();  // SIGTERM: the pty closes under the streamer
    const std::string err = sim_->stderr_text();
    if (!run.wait(30)) return problem("cncstream did not end within 30 s after the simulator died");
    const std::string out = run.output();
    if (run.code() != 1 || out.find("outcome: disconnected") == std::string::npos ||
        out.find("the controller went away: nothing more will be sent") == std::string::npos)
      problem("after the simulator died cncstream said (exit " + std::to_string(run.code()) + "):\n" + out);
    check_listed(rec, "disconnected");
    const auto pos = final_position(err);
    if (!pos) return problem("the simulator gave no final position:\n" + err);
    const fs::path saved = result_;
    start_sim({"--stock-from", saved.string(), "--position", *pos});
  }

  void fill_resumed_after() {
    for (std::size_t i = 0; i < report_.kills.size() && i < resume_logs_.size(); ++i) {
      std::ifstream f(opt_.dir / ("run" + std::to_string(resume_logs_[i]) + ".log"));
      std::stringstream s;
      s << f.rdbuf();
      report_.kills[i].resumed_after = resumed_after(s.str());
    }
  }

  void compare_surfaces() {
    const auto ref = cncstream::cam::read_height_field(reference_);
    const auto got = cncstream::cam::read_height_field(result_);
    if (ref.z.size() != got.z.size()) return problem("the result grids differ in size");
    report_.nodes = ref.z.size();
    double worst = 0;
    for (std::size_t i = 0; i < ref.z.size(); ++i) worst = std::max(worst, std::fabs(double(ref.z[i]) - double(got.z[i])));
    report_.max_height_diff_mm = worst;
  }

  CrashOptions opt_;
  std::mt19937_64 rng_;
  std::vector<std::string> env_;
  fs::path program_, reference_, db_, result_;
  std::unique_ptr<Journal> journal_;
  std::unique_ptr<simtest::SimProcess> sim_;
  int sims_ = 0;
  std::vector<int> resume_logs_;  // the run number of the resume after each kill
  CrashReport report_;
};

}  // namespace

CrashReport run_crash_resume(const CrashOptions& options) { return CrashRun(options).run(); }

}  // namespace reliability
