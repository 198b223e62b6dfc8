#pragma once
// Runs the cncsim program and talks to it through its pty, as a host would.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace simtest {

class SimProcess {
 public:
  explicit SimProcess(std::vector<std::string> args) {
    err_path_ = "/tmp/cncsim_test_" + std::to_string(getpid()) + "_" + std::to_string(counter()++) + ".err";
    int out[2];
    if (pipe(out) != 0) throw std::runtime_error("pipe");
    pid_ = fork();
    if (pid_ == 0) {
      dup2(out[1], 1);
      const int err = open(err_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(err, 2);
      close(out[0]);
      std::vector<char*> argv;
      static std::string exe = std::string(CNCSTREAM_BINARY_DIR) + "/cncsim";
      argv.push_back(exe.data());
      for (auto& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      execv(exe.c_str(), argv.data());
      _exit(127);
    }
    close(out[1]);
    // First stdout line: the slave path.
    std::string line;
    char c;
    while (read(out[0], &c, 1) == 1 && c != '\n') line.push_back(c);
    close(out[0]);
    slave_ = line;
    if (slave_.empty()) throw std::runtime_error("cncsim printed no pty path: " + stderr_text());
  }
  ~SimProcess() {
    if (pid_ > 0 && !exited_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    std::remove(err_path_.c_str());
  }
  const std::string& slave() const { return slave_; }
  // SIGTERM (unless it already exited) and the exit code.
  int stop() {
    if (!exited_) kill(pid_, SIGTERM);
    return wait();
  }
  int wait() {
    if (!exited_) {
      int st = 0;
      waitpid(pid_, &st, 0);
      exited_ = true;
      code_ = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
    }
    return code_;
  }
  std::string stderr_text() const {
    std::ifstream f(err_path_);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
  }

 private:
  static int& counter() { static int c = 0; return c; }
  pid_t pid_ = -1;
  bool exited_ = false;
  int code_ = -1;
  std::string slave_, err_path_;
};

class Port {
 public:
  explicit Port(const std::string& path) {
    fd_ = open(path.c_str(), O_RDWR | O_NOCTTY);
    if (fd_ < 0) throw std::runtime_error("open " + path + ": " + std::strerror(errno));
    termios t{};
    tcgetattr(fd_, &t);
    cfmakeraw(&t);
    tcsetattr(fd_, TCSANOW, &t);
  }
  ~Port() { if (fd_ >= 0) close(fd_); }
  void write_all(const std::string& s) {
    std::size_t off = 0;
    while (off < s.size()) {
      const ssize_t n = ::write(fd_, s.data() + off, s.size() - off);
      if (n <= 0) throw std::runtime_error("write failed");
      off += static_cast<std::size_t>(n);
    }
  }
  // Next line without "\r\n"; empty optional on timeout; "<EOF>" when the port goes away.
  std::string read_line(double timeout_s = 5.0) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    for (;;) {
      const auto nl = buf_.find('\n');
      if (nl != std::string::npos) {
        std::string line = buf_.substr(0, nl);
        buf_.erase(0, nl + 1);
        if (!line.empty() && line.back() == '\r') line.pop_back();
        return line;
      }
      const auto left = std::chrono::duration<double>(end - std::chrono::steady_clock::now()).count();
      if (left <= 0) return "<TIMEOUT>";
      pollfd p{fd_, POLLIN, 0};
      poll(&p, 1, static_cast<int>(left * 1000) + 1);
      if (p.revents & (POLLIN | POLLHUP | POLLERR)) {
        char tmp[4096];
        const ssize_t n = ::read(fd_, tmp, sizeof tmp);
        if (n <= 0) return "<EOF>";
        buf_.append(tmp, static_cast<std::size_t>(n));
      }
    }
  }
  // Reads lines until one satisfies pred (or timeout); returns it.
  template <typename Pred>
  std::string read_until(Pred pred, double timeout_s = 5.0) {
    for (;;) {
      std::string l = read_line(timeout_s);
      if (l == "<TIMEOUT>" || l == "<EOF>" || pred(l)) return l;
    }
  }

 private:
  int fd_ = -1;
  std::string buf_;
};

}  // namespace simtest
