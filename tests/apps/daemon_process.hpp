#pragma once
// The cncstreamd program as a child process, for tests that run the
// programs the way an operator does. Its output goes to a log file.
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

// cncstreamd with `args`; its journal goes to the tests' state folder. With
// --listen 127.0.0.1:0 it takes a port of its choosing: listen_port() reads
// it from the log (or a lock file it writes for a machine's port says it).
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

}  // namespace apptest
