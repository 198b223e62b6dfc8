#include "interrupt.hpp"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <stdexcept>

namespace cncstream::app {

namespace {

// Shared with the handler: lock-free atomics and a file descriptor only.
std::atomic<int> g_signals{0};       // signals received while the guard is up
std::atomic<int> g_first_signal{0};  // the first one's number
std::atomic<int> g_wake_fd{-1};      // write end of the guard's pipe
std::atomic<bool> g_guard_up{false};
struct sigaction g_old_int, g_old_term;

static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs lock-free atomics");

extern "C" void on_interrupt(int sig) {
  const int saved_errno = errno;
  if (g_signals.fetch_add(1) >= 1) {
    // A second signal: the operator does not want to wait for the job's checkpoint.
    static const char msg[] = "\ncncstream: interrupted again: exiting now\n";
    (void)!::write(STDERR_FILENO, msg, sizeof msg - 1);
    ::_exit(128 + sig);
  }
  g_first_signal.store(sig);
  const char byte = 's';
  (void)!::write(g_wake_fd.load(), &byte, 1);
  errno = saved_errno;
}

}  // namespace

InterruptGuard::InterruptGuard() {
  if (g_guard_up.exchange(true)) throw std::logic_error("InterruptGuard: one at a time");
  if (::pipe2(pipe_, O_CLOEXEC) != 0) {
    g_guard_up = false;
    throw std::runtime_error("InterruptGuard: pipe failed");
  }
  g_signals = 0;
  g_first_signal = 0;
  g_wake_fd = pipe_[1];
  watcher_ = std::thread([this] {
    char byte = 0;
    for (;;) {
      const ssize_t n = ::read(pipe_[0], &byte, 1);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0 || byte == 'q') return;  // the guard is going away
      source_.request_stop();
    }
  });
  struct sigaction sa {};
  sa.sa_handler = on_interrupt;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  ::sigaction(SIGINT, &sa, &g_old_int);
  ::sigaction(SIGTERM, &sa, &g_old_term);
}

InterruptGuard::~InterruptGuard() {
  ::sigaction(SIGINT, &g_old_int, nullptr);
  ::sigaction(SIGTERM, &g_old_term, nullptr);
  const char quit = 'q';
  (void)!::write(pipe_[1], &quit, 1);
  watcher_.join();
  g_wake_fd = -1;
  ::close(pipe_[0]);
  ::close(pipe_[1]);
  g_guard_up = false;
}

int InterruptGuard::exit_status() const {
  const int sig = g_first_signal.load();
  return 128 + (sig > 0 ? sig : SIGINT);
}

}  // namespace cncstream::app
