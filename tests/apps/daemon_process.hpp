#pragma once
// Programs of this build as child processes, for tests that run them the way
// an operator does: cncstreamd, or a cncstream command that runs beside the
// test's own steps. Their output goes to a log file.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "app_run.hpp"

namespace apptest {

// `program` (a file of the build folder) with `args`, stdin /dev/null, its
// journal in `state` under the tests' folder (not the user's). Stopped
// (SIGTERM, then SIGKILL after 10 s) when destroyed, if still running.
class BackgroundProgram {
 public:
  BackgroundProgram(const std::string& program, const std::vector<std::string>& args, const std::string& state) {
    static int counter = 0;
    log_ = temp_dir() / (program + std::to_string(counter++) + ".log");
    pid_ = ::fork();
    if (pid_ == 0) {
      const int fd = ::open(log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      const int null = ::open("/dev/null", O_RDONLY);
      ::dup2(null, 0);
      ::setenv("XDG_STATE_HOME", (temp_dir() / state).c_str(), 1);
      std::string exe = std::string(CNCSTREAM_BINARY_DIR) + "/" + program;
      std::vector<std::string> a = args;
      std::vector<char*> argv{exe.data()};
      for (auto& s : a) argv.push_back(s.data());
      argv.push_back(nullptr);
      ::execv(exe.c_str(), argv.data());
      ::_exit(127);
    }
  }
  ~BackgroundProgram() {
    if (pid_ <= 0 || exited()) return;
    ::kill(pid_, SIGTERM);
    // A clean stop within 10 s, else it is killed (and the test has failed elsewhere).
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (!exited()) {
      if (std::chrono::steady_clock::now() > end) {
        ::kill(pid_, SIGKILL);
        ::waitpid(pid_, nullptr, 0);
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  BackgroundProgram(const BackgroundProgram&) = delete;
  BackgroundProgram& operator=(const BackgroundProgram&) = delete;

  pid_t pid() const { return pid_; }
  std::string log() const {
    std::ifstream f(log_);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
  }
  // Whether its output says `text` within `timeout_s` (false at once if it has ended without).
  bool wait_output(const std::string& text, double timeout_s) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < end) {
      if (log().find(text) != std::string::npos) return true;
      if (exited()) return log().find(text) != std::string::npos;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return false;
  }
  // Its exit code, or -1 when it has not ended within `timeout_s`.
  int wait_exit(double timeout_s) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (!exited() && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    return exited_ && WIFEXITED(status_) ? WEXITSTATUS(status_) : -1;
  }

 private:
  bool exited() {
    if (!exited_ && ::waitpid(pid_, &status_, WNOHANG) == pid_) exited_ = true;
    return exited_;
  }
  pid_t pid_ = -1;
  int status_ = 0;
  bool exited_ = false;
  fs::path log_;
};

// cncstreamd with `args`. With --listen 127.0.0.1:0 it takes a port of its
// choosing: listen_port() reads it from the log (a lock file it writes for a
// machine's port says it too).
class DaemonProcess : public BackgroundProgram {
 public:
  explicit DaemonProcess(const std::vector<std::string>& args) : BackgroundProgram("cncstreamd", args, "daemon-state") {}
  // The port from its "listening on 127.0.0.1:PORT" line, once it is up
  // (0 when it has not said so within `timeout_s`).
  unsigned short listen_port(double timeout_s = 30) const {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < end) {
      const std::string text = log();
      const auto at = text.find("listening on 127.0.0.1:");
      if (at != std::string::npos) return static_cast<unsigned short>(std::atoi(text.c_str() + at + 23));
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return 0;
  }
};

}  // namespace apptest
