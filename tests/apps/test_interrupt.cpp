// Long commands under the terminal: the progress line (forced on with
// --progress always, since the tests have no terminal), and Ctrl-C/SIGTERM
// stopping the job with no output file left, complete-looking or temporary.
// The tests wait on the program's output, never on time.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include "app_run.hpp"

using namespace apptest;

namespace {

// The real program with stdout and stderr on one pipe read by the test.
class PipedRun {
 public:
  explicit PipedRun(const std::vector<std::string>& args) {
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error("pipe failed");
    std::vector<std::string> argv_s{(fs::path(CNCSTREAM_BINARY_DIR) / "cncstream").string()};
    argv_s.insert(argv_s.end(), args.begin(), args.end());
    pid_ = ::fork();
    if (pid_ < 0) throw std::runtime_error("fork failed");
    if (pid_ == 0) {
      const int in = ::open("/dev/null", O_RDONLY);
      ::dup2(in, 0);
      ::dup2(fds[1], 1);
      ::dup2(fds[1], 2);
      ::signal(SIGINT, SIG_DFL);
      ::signal(SIGTERM, SIG_DFL);
      std::vector<char*> argv;
      for (auto& a : argv_s) argv.push_back(a.data());
      argv.push_back(nullptr);
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
    ::close(fds[1]);
    fd_ = fds[0];
  }
  ~PipedRun() {
    if (pid_ > 0 && !reaped_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    if (fd_ >= 0) ::close(fd_);
  }
  // Reads until `text` has appeared (true) or the program closed its output
  // or `limit_s` passed (false: a hung program fails the test, not the suite).
  bool wait_for(const std::string& text, double limit_s = 120) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(limit_s);
    while (out_.find(text) == std::string::npos) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(end - std::chrono::steady_clock::now());
      if (left.count() <= 0 || !read_some(static_cast<int>(left.count()))) return false;
    }
    return true;
  }
  void signal(int sig) { ::kill(pid_, sig); }
  // Reads to the end of its output and returns its exit status (128 + signal if killed).
  int finish(double limit_s = 120) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(limit_s);
    for (;;) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(end - std::chrono::steady_clock::now());
      if (left.count() <= 0 || !read_some(static_cast<int>(left.count()))) break;
    }
    int st = 0;
    if (!eof_) {  // still talking after the limit: a hung program
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, &st, 0);
      reaped_ = true;
      return -1;
    }
    ::waitpid(pid_, &st, 0);  // its output is closed: it is exiting
    reaped_ = true;
    return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
  }
  const std::string& output() const { return out_; }

 private:
  bool read_some(int timeout_ms) {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, timeout_ms) <= 0) return false;
    char buf[4096];
    const ssize_t n = ::read(fd_, buf, sizeof buf);
    if (n <= 0) {
      eof_ = true;
      return false;
    }
    out_.append(buf, static_cast<std::size_t>(n));
    return true;
  }

  pid_t pid_ = -1;
  int fd_ = -1;
  bool reaped_ = false, eof_ = false;
  std::string out_;
};

std::string mesh(const std::string& name) { return (fs::path(CNCSTREAM_SHARED_MESHES) / name).string(); }

// A tool path that takes several seconds (about 7 s on a 2-core machine, more
// with the G-code): the lion relief at 100 mm and a fine step.
std::vector<std::string> slow_toolpath_args() {
  return {mesh("lion_head_relief.stl"), "--scale", "100", "--tool", "ball:3", "--stepover", "0.05", "--step", "0.01",
          "--stock", "none", "--strategy", "raster"};
}

// Files in `dir` whose names start with `stem` (the output and any temporary file beside it).
std::vector<std::string> files_starting(const fs::path& dir, const std::string& stem) {
  std::vector<std::string> found;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().rfind(stem, 0) == 0) found.push_back(e.path().filename().string());
  return found;
}

fs::path fresh_dir(const std::string& name) {
  const fs::path d = temp_dir() / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

}  // namespace

TEST(Interrupt, CtrlCDuringAToolPathWritesNothingAndExits130) {
  const fs::path dir = fresh_dir("interrupt_toolpath");
  const fs::path out = dir / "lion.nc";
  auto args = slow_toolpath_args();
  args.insert(args.begin(), "toolpath");
  for (const char* a : {"--progress", "always", "-o"}) args.push_back(a);
  args.push_back(out.string());
  PipedRun run(args);
  ASSERT_TRUE(run.wait_for(" elapsed")) << run.output();  // the progress line is up: the job runs
  run.signal(SIGINT);
  EXPECT_EQ(run.finish(), 130) << run.output();
  EXPECT_NE(run.output().find("cncstream: interrupted: " + out.string() + " not written"), std::string::npos)
      << run.output();
  EXPECT_FALSE(fs::exists(out));
  EXPECT_TRUE(files_starting(dir, "lion.nc").empty()) << files_starting(dir, "lion.nc").front();
  EXPECT_EQ(run.output().find("wrote"), std::string::npos) << run.output();
}

TEST(Interrupt, SigtermStopsTheJobLikeCtrlC) {
  const fs::path dir = fresh_dir("interrupt_sigterm");
  const fs::path out = dir / "lion.nc";
  auto args = slow_toolpath_args();
  args.insert(args.begin(), "toolpath");
  for (const char* a : {"--progress", "always", "-o"}) args.push_back(a);
  args.push_back(out.string());
  PipedRun run(args);
  ASSERT_TRUE(run.wait_for(" elapsed")) << run.output();
  run.signal(SIGTERM);
  EXPECT_EQ(run.finish(), 128 + SIGTERM) << run.output();
  EXPECT_NE(run.output().find("interrupted: " + out.string() + " not written"), std::string::npos) << run.output();
  EXPECT_TRUE(files_starting(dir, "lion.nc").empty());
}

TEST(Interrupt, AToolPathRunToTheEndShowsProgressTo100PercentAndClearsTheLine) {
  const fs::path dir = fresh_dir("progress_toolpath");
  const fs::path out = dir / "gear.nc";
  PipedRun run({"toolpath", mesh("gearwheel.bin.stl"), "--tool", "ball:3", "--stepover", "1", "--stock", "none", "--strategy", "raster", "--progress", "always",
                "-o", out.string()});
  EXPECT_EQ(run.finish(), 0) << run.output();
  const std::string& o = run.output();
  EXPECT_NE(o.find("\rload    0 %"), std::string::npos) << o;
  const auto done = o.find("\rdone  100 %");
  ASSERT_NE(done, std::string::npos) << o;
  EXPECT_NE(o.find("\r\x1b[K", done), std::string::npos) << "the line is cleared at the end";
  EXPECT_NE(o.find("wrote " + out.string()), std::string::npos) << o;
  EXPECT_TRUE(fs::is_regular_file(out));
  EXPECT_EQ(files_starting(dir, "gear.nc"), std::vector<std::string>{"gear.nc"});
}

TEST(Interrupt, NoProgressLineWithoutATerminalUnlessAskedFor) {
  const fs::path dir = fresh_dir("progress_auto");
  for (const char* mode : {"auto", "never"}) {
    PipedRun run({"toolpath", mesh("gearwheel.bin.stl"), "--tool", "ball:3", "--stepover", "1", "--stock", "none", "--strategy", "raster", "--progress", mode,
                  "-o", (dir / "gear.nc").string()});
    EXPECT_EQ(run.finish(), 0) << run.output();
    EXPECT_EQ(run.output().find(" elapsed"), std::string::npos) << mode << ": " << run.output();
    EXPECT_EQ(run.output().find('\r'), std::string::npos) << mode;
  }
}

// The main command's generation before streaming: Ctrl-C stops it, nothing
// is written and the simulator is never started.
TEST(Interrupt, CtrlCWhileTheMainCommandGeneratesStreamsNothing) {
  const fs::path dir = fresh_dir("interrupt_stream");
  const fs::path out = dir / "lion.nc";
  auto args = slow_toolpath_args();
  args.insert(args.begin(), "sim");
  args.insert(args.begin(), mesh("lion_head_relief.stl"));
  args.erase(args.begin() + 2);  // the mesh again (slow_toolpath_args starts with it)
  for (const char* a : {"--progress", "always", "--yes", "--no-journal", "-o"}) args.push_back(a);
  args.push_back(out.string());
  PipedRun run(args);
  ASSERT_TRUE(run.wait_for(" elapsed")) << run.output();
  run.signal(SIGINT);
  EXPECT_EQ(run.finish(), 130) << run.output();
  EXPECT_NE(run.output().find("interrupted: " + out.string() + " not written, nothing streamed"), std::string::npos)
      << run.output();
  EXPECT_EQ(run.output().find("simulator:"), std::string::npos) << run.output();
  EXPECT_TRUE(files_starting(dir, "lion.nc").empty());
}

TEST(Interrupt, CtrlCDuringAGridLeavesNeitherDataNorSidecar) {
  const fs::path dir = fresh_dir("interrupt_clgrid");
  const fs::path out = dir / "lion.f32";
  PipedRun run({"clgrid", mesh("lion_head_relief.stl"), "--scale", "100", "--tool", "ball:3", "--grid", "0.01",
                "--progress", "always", "-o", out.string()});
  ASSERT_TRUE(run.wait_for("CL grid")) << run.output();
  run.signal(SIGINT);
  EXPECT_EQ(run.finish(), 130) << run.output();
  EXPECT_NE(run.output().find("interrupted: " + out.string() + " not written"), std::string::npos) << run.output();
  EXPECT_TRUE(files_starting(dir, "lion").empty());
}

TEST(Interrupt, AGridRunToTheEndWritesDataAndSidecarOnly) {
  const fs::path dir = fresh_dir("progress_clgrid");
  const fs::path out = dir / "gear.f32";
  PipedRun run({"clgrid", mesh("gearwheel.bin.stl"), "--tool", "ball:3", "--grid", "0.5", "--progress", "always", "-o",
                out.string()});
  EXPECT_EQ(run.finish(), 0) << run.output();
  EXPECT_NE(run.output().find("\rdone  100 %"), std::string::npos) << run.output();
  auto files = files_starting(dir, "gear");
  std::sort(files.begin(), files.end());
  EXPECT_EQ(files, (std::vector<std::string>{"gear.f32", "gear.f32.txt"}));
}

namespace {

// `command` (select or plan) on the lion head with two cutters, stopped by
// Ctrl-C once its progress line shows: exit 130, the message naming what was
// not written (`what` in `dir`), and `dir` missing or empty.
void expect_ctrl_c_leaves_no_folder(const std::string& command, const std::string& what, const fs::path& dir) {
  PipedRun run({command, mesh("lion_head_relief.stl"), "--scale", "100", "--tools", "ball:3,bull:3:0.5", "--stepover",
                "0.1", "--progress", "always", "-o", dir.string()});
  ASSERT_TRUE(run.wait_for(" elapsed")) << run.output();
  run.signal(SIGINT);
  EXPECT_EQ(run.finish(), 130) << run.output();
  EXPECT_NE(run.output().find("cncstream: interrupted: no " + what + " written in " + dir.string()), std::string::npos)
      << run.output();
  EXPECT_TRUE(!fs::exists(dir) || fs::is_empty(dir));
}

}  // namespace

TEST(Interrupt, CtrlCDuringASelectionWritesNoReport) {
  expect_ctrl_c_leaves_no_folder("select", "report", fresh_dir("interrupt_select") / "report");
}

TEST(Interrupt, CtrlCDuringAPlanWritesNoProgram) {
  expect_ctrl_c_leaves_no_folder("plan", "plan", fresh_dir("interrupt_plan") / "plan");
}
