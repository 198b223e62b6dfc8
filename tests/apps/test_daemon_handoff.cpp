// `cncstream FILE PORT` while the daemon owns PORT: the same command hands
// the job to cncstreamd (upload, create, plan, start) and follows it to its
// end with the local run's exit code; `cncstream status` shows the daemon's
// machine. The machine is the cncsim program on a pty (the daemon's `sim` is
// in-process and owns no port); lock files go to a private folder that the
// daemon, the CLI and this test share through $CNCSTREAM_LOCK_DIR.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <nlohmann/json.hpp>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "app_run.hpp"
#include "cncstream/transport/port_lock.hpp"
#include "sim/pty_process.hpp"

using namespace apptest;
namespace tr = cncstream::transport;

namespace {

// cncstreamd on a loopback port of its choosing (--listen 127.0.0.1:0): the
// address is learned from the lock file it writes for the machine's port.
class DaemonProcess {
 public:
  explicit DaemonProcess(const std::vector<std::string>& args) {
    log_ = temp_dir() / ("cncstreamd" + std::to_string(counter()++) + ".log");
    pid_ = ::fork();
    if (pid_ == 0) {
      const int fd = ::open(log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      const int null = ::open("/dev/null", O_RDONLY);
      ::dup2(null, 0);
      // The daemon's journal goes to this test's state folder, not the user's.
      ::setenv("XDG_STATE_HOME", (temp_dir() / "daemon-state").c_str(), 1);
      std::vector<std::string> a = args;
      static std::string exe = std::string(CNCSTREAM_BINARY_DIR) + "/cncstreamd";
      std::vector<char*> argv{exe.data()};
      for (auto& s : a) argv.push_back(s.data());
      argv.push_back(nullptr);
      ::execv(exe.c_str(), argv.data());
      ::_exit(127);
    }
  }
  ~DaemonProcess() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGTERM);
    // A clean stop within 10 s, else it is killed (and the test has failed elsewhere).
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (::waitpid(pid_, nullptr, WNOHANG) == 0) {
      if (std::chrono::steady_clock::now() > end) {
        ::kill(pid_, SIGKILL);
        ::waitpid(pid_, nullptr, 0);
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  pid_t pid() const { return pid_; }
  std::string log() const {
    std::ifstream f(log_);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
  }

 private:
  static int& counter() {
    static int c = 0;
    return c;
  }
  pid_t pid_ = -1;
  fs::path log_;
};

// The daemon's lock on `port`, once it has opened it (deadline 30 s).
std::optional<tr::PortOwner> wait_for_daemon_lock(const std::string& port, pid_t daemon) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (std::chrono::steady_clock::now() < end) {
    if (auto o = tr::port_owner(port); o && o->pid == daemon && !o->api.empty()) return o;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return std::nullopt;
}

class DaemonHandoff : public ::testing::Test {
 protected:
  void SetUp() override {
    static int n = 0;
    const fs::path locks = temp_dir() / ("handoff-locks" + std::to_string(n));
    fs::create_directories(locks);
    ::setenv("CNCSTREAM_LOCK_DIR", locks.c_str(), 1);
    sim = std::make_unique<simtest::SimProcess>(std::vector<std::string>{"--speed", sim_speed(), "--strict"});
    daemon = std::make_unique<DaemonProcess>(std::vector<std::string>{
        "--listen", "127.0.0.1:0", "--data", (temp_dir() / ("handoff-data" + std::to_string(n++))).string(),
        "--machine", "router=" + sim->slave()});
    const auto owner = wait_for_daemon_lock(sim->slave(), daemon->pid());
    ASSERT_TRUE(owner) << "the daemon did not take " << sim->slave() << ":\n" << daemon->log();
    EXPECT_EQ(owner->program, "cncstreamd");
    api = owner->api;
    ::setenv("CNCSTREAM_DAEMON", api.c_str(), 1);
  }
  void TearDown() override {
    daemon.reset();
    sim.reset();
    ::unsetenv("CNCSTREAM_LOCK_DIR");
    ::unsetenv("CNCSTREAM_DAEMON");
  }
  virtual std::string sim_speed() const { return "max"; }
  std::unique_ptr<simtest::SimProcess> sim;
  std::unique_ptr<DaemonProcess> daemon;
  std::string api;
};

// A machine in real time, for a job that is stopped while it runs.
class SlowDaemonHandoff : public DaemonHandoff {
 protected:
  std::string sim_speed() const override { return "1"; }
};

}  // namespace

TEST_F(DaemonHandoff, GcodeFileIsHandedToTheDaemonAndFollowedToItsEnd) {
  const auto prog = temp_dir() / "handoff.nc";
  {
    std::ofstream f(prog);
    f << "G21 G90 G94\nG1 X10 F2000\nG1 Y10\nG1 X0\nG1 Y0\nM2\n";
  }
  const auto r = run_cncstream({prog.string(), sim->slave(), "--yes"}, 120);
  EXPECT_EQ(r.code, 0) << r.out << "\n--- daemon:\n" << daemon->log();
  EXPECT_TRUE(r.has(sim->slave() + " is owned by cncstreamd (pid " + std::to_string(daemon->pid()) + ", API " + api +
                    ")"))
      << r.out;
  EXPECT_TRUE(r.has("handing the job to it")) << r.out;
  EXPECT_TRUE(r.has("6 lines, estimated machining time")) << r.out;
  EXPECT_TRUE(r.has("outcome: completed")) << r.out;
  EXPECT_TRUE(r.has("last answered file line 6")) << r.out;
  // The daemon still owns the port; the CLI never opened it.
  const auto owner = tr::port_owner(sim->slave());
  ASSERT_TRUE(owner);
  EXPECT_EQ(owner->pid, daemon->pid());
}

// A small part: uploads are limited by the daemon's configuration, and the
// tool path is generated by the daemon before the job starts.
static std::string gearwheel() { return std::string(CNCSTREAM_SHARED_MESHES) + "/gearwheel.bin.stl"; }

TEST_F(DaemonHandoff, StlJobWithTheToolPathOptionsRunsOnTheDaemon) {
  const auto out = temp_dir() / "handoff-gearwheel.nc";
  const auto r = run_cncstream(
      {gearwheel(), sim->slave(), "--tool", "ball:3.175", "--stepover", "3", "--feed", "1500", "--yes", "-o", out.string()},
      300);
  EXPECT_EQ(r.code, 0) << r.out << "\n--- daemon:\n" << daemon->log();
  EXPECT_TRUE(r.has("plan for " + gearwheel() + " (tool path by the daemon at " + api)) << r.out;
  EXPECT_TRUE(r.has("tool: 3.175 mm ball-nose end mill")) << r.out;
  // The daemon's operations: roughing from the part's block with the same
  // ball (no tool change), then the finishing rows at the stepover asked.
  EXPECT_TRUE(r.has("roughing: T1 ball:3.175")) << r.out;
  EXPECT_TRUE(r.has("finishing: T1 ball:3.175")) << r.out;
  EXPECT_TRUE(r.has("rows 3 mm apart along X")) << r.out;
  EXPECT_TRUE(r.has("feed 1500 mm/min")) << r.out;
  EXPECT_TRUE(r.has("outcome: completed")) << r.out;
  // The program the daemon generated, written where -o said.
  std::ifstream f(out);
  std::string first;
  std::getline(f, first);
  EXPECT_FALSE(first.empty()) << "no program written to " << out;
}

TEST_F(DaemonHandoff, WithoutYesAndWithoutATerminalTheStlJobIsNotStarted) {
  const auto r =
      run_cncstream({gearwheel(), sim->slave(), "--tool", "ball:3.175", "--stepover", "3", "--stock", "none"}, 300);
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_TRUE(r.has("pass --yes")) << r.out;
  EXPECT_FALSE(r.has("outcome:")) << r.out;
}

TEST_F(DaemonHandoff, StatusShowsTheDaemonsMachine) {
  const auto r = run_cncstream({"status", "--json"});
  ASSERT_EQ(r.code, 0) << r.out;
  const auto doc = nlohmann::json::parse(r.out, nullptr, false);
  ASSERT_FALSE(doc.is_discarded()) << r.out;
  ASSERT_TRUE(doc["daemon"].is_object()) << r.out;
  EXPECT_EQ(doc["daemon"]["url"], api);
  ASSERT_EQ(doc["daemon"]["machines"].size(), 1u) << r.out;
  EXPECT_EQ(doc["daemon"]["machines"][0]["name"], "router");
  EXPECT_TRUE(doc["daemon"]["machines"][0]["queue"].is_array());
  const auto text = run_cncstream({"status"});
  EXPECT_TRUE(text.has("cncstreamd at " + api)) << text.out;
  EXPECT_TRUE(text.has("  router  " + sim->slave() + "  ")) << text.out;
}

// The command's time-out stops the daemon's job (the controlled stop, as an
// API call) and the command exits as a local run that did not complete.
TEST_F(SlowDaemonHandoff, TimeOutStopsTheJobOnTheDaemon) {
  const auto prog = temp_dir() / "handoff-slow.nc";
  {
    std::ofstream f(prog);
    f << "G21 G90 G94\n";
    for (int i = 0; i < 200; ++i) f << "G1 X" << (i % 2 ? 0 : 20) << " Y" << i * 0.1 << " F1000\n";
    f << "M2\n";
  }
  const auto r = run_cncstream({prog.string(), sim->slave(), "--yes", "--timeout", "2"}, 120);
  EXPECT_EQ(r.code, 1) << r.out << "\n--- daemon:\n" << daemon->log();
  EXPECT_TRUE(r.has("time-out after 0:02: stopping the job")) << r.out;
  EXPECT_TRUE(r.has("outcome: stopped")) << r.out;
  EXPECT_FALSE(r.has("last answered file line 202")) << r.out;
}
