#include "cncsim/pty_frontend.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/inotify.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <system_error>

namespace cncsim {
namespace {

std::string errno_text(const char* what) {
  return std::string(what).append(": ").append(std::generic_category().message(errno));
}

}  // namespace

PtyFrontEnd::PtyFrontEnd(Machine& machine, PtyOptions options)
    : machine_(machine), options_(std::move(options)) {
  master_ = posix_openpt(O_RDWR | O_NOCTTY);
  if (master_ < 0) throw PtyError(errno_text("posix_openpt"));
  if (grantpt(master_) != 0 || unlockpt(master_) != 0) throw PtyError(errno_text("grantpt/unlockpt"));
  char name[128];  // "/dev/pts/N"
  if (const int e = ptsname_r(master_, name, sizeof name); e != 0) {
    errno = e;
    throw PtyError(errno_text("ptsname_r"));
  }
  slave_path_ = name;
  slave_keepalive_ = open(name, O_RDWR | O_NOCTTY);
  if (slave_keepalive_ < 0) throw PtyError(errno_text(("open " + slave_path_).c_str()));
  termios tio{};
  if (tcgetattr(slave_keepalive_, &tio) != 0) throw PtyError(errno_text("tcgetattr"));
  cfmakeraw(&tio);  // no echo, no line discipline: bytes pass as on a UART
  cfsetispeed(&tio, B115200);
  cfsetospeed(&tio, B115200);
  if (tcsetattr(slave_keepalive_, TCSANOW, &tio) != 0) throw PtyError(errno_text("tcsetattr"));
  fcntl(master_, F_SETFL, fcntl(master_, F_GETFL) | O_NONBLOCK);
  // Without inotify the pty still works; only a killed host's exclusive mode stays.
  host_watch_ = inotify_init1(IN_NONBLOCK | IN_CLOEXEC);
  if (host_watch_ >= 0 && inotify_add_watch(host_watch_, name, IN_OPEN | IN_CLOSE_WRITE | IN_CLOSE_NOWRITE) < 0) {
    close(host_watch_);
    host_watch_ = -1;
  }
  if (options_.link) {
    std::error_code ec;
    std::filesystem::remove(*options_.link, ec);
    std::filesystem::create_symlink(slave_path_, *options_.link, ec);
    if (ec) throw PtyError("cannot make link " + options_.link->string() + ": " + ec.message());
  }
}

PtyFrontEnd::~PtyFrontEnd() { close_all(); }

void PtyFrontEnd::close_all() {
  if (host_watch_ >= 0) close(host_watch_);
  if (master_ >= 0) close(master_);
  if (slave_keepalive_ >= 0) close(slave_keepalive_);
  master_ = slave_keepalive_ = host_watch_ = -1;
  if (options_.link) {
    std::error_code ec;
    if (std::filesystem::is_symlink(*options_.link, ec)) std::filesystem::remove(*options_.link, ec);
  }
}

void PtyFrontEnd::flush_output() {
  pending_out_ += machine_.take_output();
  while (!pending_out_.empty()) {
    const ssize_t n = write(master_, pending_out_.data(), pending_out_.size());
    if (n > 0) {
      pending_out_.erase(0, static_cast<std::size_t>(n));
    } else {
      break;  // the host is not reading: keep it for later
    }
  }
}

void PtyFrontEnd::watch_host() {
  alignas(inotify_event) char buf[4096];
  for (;;) {
    const ssize_t n = read(host_watch_, buf, sizeof buf);
    if (n <= 0) return;
    for (ssize_t at = 0; at < n;) {
      const auto* e = reinterpret_cast<const inotify_event*>(buf + at);
      if (e->mask & IN_OPEN) ++host_opens_;
      if (e->mask & (IN_CLOSE_WRITE | IN_CLOSE_NOWRITE)) {
        host_opens_ = host_opens_ > 0 ? host_opens_ - 1 : 0;
        if (host_opens_ == 0) ioctl(slave_keepalive_, TIOCNXCL);
      }
      at += static_cast<ssize_t>(sizeof(inotify_event) + e->len);
    }
  }
}

PtyFrontEnd::Exit PtyFrontEnd::run(const std::atomic<bool>& stop) {
  using clock = std::chrono::steady_clock;
  const bool max_speed = options_.speed <= 0;
  // At --speed max the machine skips its waits itself; time still flows fast
  // so that motion left in the planner finishes when the host goes quiet.
  auto last = clock::now();
  char buf[4096];
  while (!stop.load()) {
    flush_output();
    pollfd fds[2] = {{master_, POLLIN, 0}, {host_watch_, POLLIN, 0}};
    const int timeout_ms = machine_.busy() || !pending_out_.empty() ? 1 : 10;
    poll(fds, host_watch_ >= 0 ? 2 : 1, timeout_ms);
    if (fds[1].revents & POLLIN) watch_host();
    const pollfd& p = fds[0];
    if (p.revents & POLLIN) {
      for (;;) {
        const ssize_t n = read(master_, buf, sizeof buf);
        if (n <= 0) break;
        machine_.receive(std::string_view(buf, static_cast<std::size_t>(n)));
        if (machine_.vanished()) break;
      }
    }
    const auto now = clock::now();
    const double wall = std::chrono::duration<double>(now - last).count();
    last = now;
    // A stall fault lasts its seconds on the wall clock even at --speed max.
    const double scale = max_speed ? (machine_.stalled() ? 1.0 : 1000.0) : options_.speed;
    machine_.advance(wall * scale);
    if (machine_.vanished()) {
      // Let the host read the last answers before the port disappears: a
      // hangup discards what is still queued on the slave side.
      // Written bytes reach the slave's queue asynchronously, so the queue
      // must be seen empty twice, 10 ms apart (up to 1 s in all).
      int quiet = 0;
      for (int i = 0; i < 100 && quiet < 2; ++i) {
        usleep(10000);
        flush_output();
        int unread = 0;
        const bool empty = pending_out_.empty() && (ioctl(slave_keepalive_, FIONREAD, &unread) != 0 || unread == 0);
        quiet = empty ? quiet + 1 : 0;
      }
      close_all();
      return Exit::Vanished;
    }
  }
  flush_output();
  return Exit::Stopped;
}

}  // namespace cncsim
