// One owner per serial port: the lock file (who, with a PID to check), the
// kernel's TIOCEXCL (for programs that ignore lock files), symlinks as one
// port, stale locks of dead processes taken over, and release on close and
// on exit. Ptys stand in for USB serial ports; every test has a private lock
// folder ($CNCSTREAM_LOCK_DIR) so it never meets other programs' locks.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <linux/capability.h>
#include <signal.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <boost/asio/io_context.hpp>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "cncstream/transport/port_lock.hpp"
#include "cncstream/transport/serial_transport.hpp"
#include "support/pty.hpp"

using namespace cncstream::transport;
namespace fs = std::filesystem;

namespace {

using test_support::Pty;

std::string read_text(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// Runs `fn` in a child process and returns its exit code.
template <typename Fn>
int in_child(Fn fn) {
  const pid_t pid = ::fork();
  if (pid == 0) ::_exit(fn());
  int st = 0;
  ::waitpid(pid, &st, 0);
  return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
}

// The kernel lets CAP_SYS_ADMIN through TIOCEXCL; tests run as root here,
// so a child that must be refused drops that capability first.
bool drop_sys_admin() {
  __user_cap_header_struct h{_LINUX_CAPABILITY_VERSION_3, 0};
  __user_cap_data_struct d[2]{};
  if (::syscall(SYS_capget, &h, d) != 0) return false;
  d[CAP_SYS_ADMIN / 32].effective &= ~(1u << (CAP_SYS_ADMIN % 32));
  return ::syscall(SYS_capset, &h, d) == 0;
}

// A PID that no process has: a child that has exited and been reaped.
pid_t dead_pid() {
  const pid_t pid = ::fork();
  if (pid == 0) ::_exit(0);
  ::waitpid(pid, nullptr, 0);
  return pid;
}

class PortLockTest : public ::testing::Test {
 protected:
  void SetUp() override {
    static int n = 0;
    dir = fs::temp_directory_path() / ("cncstream_locks_" + std::to_string(::getpid()) + "_" + std::to_string(n++));
    fs::create_directories(dir);
    ::setenv("CNCSTREAM_LOCK_DIR", dir.c_str(), 1);
    set_lock_identity({"lock-test", ""});
  }
  void TearDown() override {
    ::unsetenv("CNCSTREAM_LOCK_DIR");
    set_lock_identity({});
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
  fs::path lock_of(const std::string& dev) const { return dir / lock_file_name(resolve_device(dev)); }
  fs::path dir;
  boost::asio::io_context io;
};

}  // namespace

TEST(PortLockNames, UucpNamesUnderDev) {
  EXPECT_EQ(lock_file_name("/dev/ttyUSB0"), "LCK..ttyUSB0");
  EXPECT_EQ(lock_file_name("/dev/pts/3"), "LCK..pts_3");
}

TEST_F(PortLockTest, SecondOpenInAnotherProcessNamesTheFirstOwner) {
  Pty pty;
  int ready[2], quit[2];
  ASSERT_EQ(::pipe(ready), 0);
  ASSERT_EQ(::pipe(quit), 0);
  const pid_t holder = ::fork();
  if (holder == 0) {
    set_lock_identity({"holder-prog", "http://127.0.0.1:8999"});
    boost::asio::io_context cio;
    SerialTransport t(cio, SerialSettings{});
    try {
      t.open(pty.slave);
    } catch (...) {
      ::_exit(3);
    }
    char c = 1;
    if (::write(ready[1], &c, 1) != 1) ::_exit(4);
    ::read(quit[0], &c, 1);  // until the parent says so
    ::_exit(0);
  }
  char c = 0;
  ASSERT_EQ(::read(ready[0], &c, 1), 1) << "the holder could not open the pty";

  SerialTransport t(io, SerialSettings{});
  try {
    t.open(pty.slave);
    FAIL() << "a second owner opened " << pty.slave;
  } catch (const PortBusyError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("cannot open " + pty.slave + ": it is in use by holder-prog (pid " + std::to_string(holder) +
                     ", API http://127.0.0.1:8999) since "),
              std::string::npos)
        << m;
    EXPECT_EQ(e.owner().pid, holder);
    EXPECT_EQ(e.owner().api, "http://127.0.0.1:8999");
  }
  // What the CLI asks before handing a job over.
  const auto owner = port_owner(pty.slave);
  ASSERT_TRUE(owner);
  EXPECT_EQ(owner->pid, holder);
  EXPECT_EQ(owner->program, "holder-prog");
  EXPECT_TRUE(owner->alive);

  // The holder dies without a word (SIGKILL: no destructor, no atexit): its
  // lock file stays, but its PID and flock are gone, so the port is free.
  ::kill(holder, SIGKILL);
  ::waitpid(holder, nullptr, 0);
  EXPECT_TRUE(fs::exists(lock_of(pty.slave)));
  EXPECT_FALSE(port_owner(pty.slave));
  ASSERT_NO_THROW(t.open(pty.slave));
  EXPECT_NE(t.lock_note().find("removed the stale lock file " + lock_of(pty.slave).string() + " of holder-prog (pid " +
                               std::to_string(holder) + ", API http://127.0.0.1:8999, no longer running)"),
            std::string::npos)
      << t.lock_note();
  EXPECT_NE(read_text(lock_of(pty.slave)).find(std::to_string(::getpid()) + " lock-test "), std::string::npos);
  ::close(ready[0]), ::close(ready[1]), ::close(quit[0]), ::close(quit[1]);
}

TEST_F(PortLockTest, ASymlinkIsTheSamePortAndCloseReleasesIt) {
  Pty pty;
  const fs::path link = dir / "by-id-usb-1a86_USB_Serial-if00-port0";
  fs::create_symlink(pty.slave, link);
  SerialTransport a(io, SerialSettings{});
  a.open(link.string());
  EXPECT_TRUE(fs::exists(lock_of(pty.slave)));
  EXPECT_EQ(a.lock().device(), resolve_device(pty.slave));

  SerialTransport b(io, SerialSettings{});
  try {
    b.open(pty.slave);
    FAIL() << "opened " << pty.slave << " while its symlink was open";
  } catch (const PortBusyError& e) {
    EXPECT_NE(std::string(e.what()).find("in use by lock-test (pid " + std::to_string(::getpid()) + ")"),
              std::string::npos)
        << e.what();
  }
  // ...and the other way round, naming both the link and the device.
  SerialTransport c(io, SerialSettings{});
  EXPECT_THROW(c.open(link.string()), PortBusyError);

  a.close();
  EXPECT_FALSE(fs::exists(lock_of(pty.slave)));
  EXPECT_FALSE(port_owner(pty.slave));
  EXPECT_NO_THROW(b.open(pty.slave));
}

TEST_F(PortLockTest, StaleLockOfADeadProgramIsTakenOverWithAMessage) {
  Pty pty;
  const pid_t gone = dead_pid();
  {
    std::ofstream f(lock_of(pty.slave));
    char line[64];
    std::snprintf(line, sizeof line, "%10ld minicom operator\n", static_cast<long>(gone));
    f << line;
  }
  SerialTransport t(io, SerialSettings{});
  ASSERT_NO_THROW(t.open(pty.slave));
  EXPECT_NE(t.lock_note().find("removed the stale lock file"), std::string::npos) << t.lock_note();
  EXPECT_NE(t.lock_note().find("minicom (pid " + std::to_string(gone) + ", no longer running)"), std::string::npos)
      << t.lock_note();
  // The file is ours now, in the form minicom reads (PID first, ten columns).
  const std::string text = read_text(lock_of(pty.slave));
  char first[32];
  std::snprintf(first, sizeof first, "%10ld lock-test", static_cast<long>(::getpid()));
  EXPECT_EQ(text.rfind(first, 0), 0u) << text;
}

TEST_F(PortLockTest, ALiveForeignLockIsHonoured) {
  Pty pty;
  // minicom's lock file for a running process (this test's parent stands in).
  {
    std::ofstream f(lock_of(pty.slave));
    f << "     " << ::getppid() << " minicom operator\n";
  }
  SerialTransport t(io, SerialSettings{});
  try {
    t.open(pty.slave);
    FAIL() << "opened a port minicom holds";
  } catch (const PortBusyError& e) {
    EXPECT_NE(std::string(e.what()).find("it is in use by minicom (pid " + std::to_string(::getppid()) + ")"),
              std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(fs::exists(lock_of(pty.slave)));  // not ours to remove
}

TEST_F(PortLockTest, TiocexclRefusesARawOpenFromAnotherProcessUntilClosed) {
  Pty pty;
  SerialTransport t(io, SerialSettings{});
  t.open(pty.slave);
  // 0: refused with EBUSY; 1: opened; 2: another error; 5: could not drop CAP_SYS_ADMIN.
  auto raw_open = [&] {
    return in_child([&] {
      if (::geteuid() == 0 && !drop_sys_admin()) return 5;
      const int fd = ::open(pty.slave.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
      if (fd >= 0) return 1;
      return errno == EBUSY ? 0 : 2;
    });
  };
  EXPECT_EQ(raw_open(), 0) << "a program that ignores lock files opened " << pty.slave;
  t.close();  // TIOCNXCL: the pty lives on (its master is open) and must open again
  EXPECT_EQ(raw_open(), 1);
}

TEST_F(PortLockTest, TiocexclOfAProgramWithoutLockFileIsNamed) {
  Pty pty;
  // Another program holds the tty exclusively and writes no lock file.
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t other = ::fork();
  if (other == 0) {
    const int fd = ::open(pty.slave.c_str(), O_RDWR | O_NOCTTY);
    if (fd < 0 || ::ioctl(fd, TIOCEXCL) != 0) ::_exit(3);
    char c = 1;
    if (::write(ready[1], &c, 1) != 1) ::_exit(4);
    ::pause();
    ::_exit(0);
  }
  char c = 0;
  ASSERT_EQ(::read(ready[0], &c, 1), 1);
  const int code = in_child([&] {
    if (::geteuid() == 0 && !drop_sys_admin()) return 5;
    SerialTransport t(io, SerialSettings{});
    try {
      t.open(pty.slave);
      return 1;
    } catch (const PortBusyError& e) {
      const std::string m = e.what();
      const bool named = m.find("it is in use by another process (TIOCEXCL)") != std::string::npos &&
                         m.find("(pid " + std::to_string(other) + ")") != std::string::npos;
      if (!named) std::fprintf(stderr, "message: %s\n", m.c_str());
      return named ? 0 : 6;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "not busy: %s\n", e.what());
      return 2;
    }
  });
  ::kill(other, SIGKILL);
  ::waitpid(other, nullptr, 0);
  ::close(ready[0]), ::close(ready[1]);
  EXPECT_EQ(code, 0);
  // Refused by the kernel, so no lock file may be left behind.
  EXPECT_FALSE(fs::exists(lock_of(pty.slave)));
}

TEST_F(PortLockTest, ExitWithoutDestructorsRemovesTheLockFile) {
  Pty pty;
  const fs::path file = lock_of(pty.slave);
  const int code = in_child([&] {
    auto* lock = new PortLock(PortLock::acquire(pty.slave));  // never destroyed
    if (!lock->held() || !fs::exists(file)) return 2;
    std::exit(0);  // atexit handlers run, destructors of the heap object do not
  });
  EXPECT_EQ(code, 0);
  EXPECT_FALSE(fs::exists(file));
}

TEST_F(PortLockTest, ListingShowsLiveAndStaleOwners) {
  Pty live, stale;
  PortLock held = PortLock::acquire(live.slave);
  {
    std::ofstream f(lock_of(stale.slave));
    f << "     " << dead_pid() << " picocom operator\n";
  }
  const auto owners = list_port_owners();
  ASSERT_EQ(owners.size(), 2u);
  int seen = 0;
  for (const auto& o : owners) {
    if (o.device == resolve_device(live.slave)) {
      ++seen;
      EXPECT_TRUE(o.alive);
      EXPECT_EQ(o.pid, ::getpid());
      EXPECT_EQ(o.program, "lock-test");
    } else if (o.device == resolve_device(stale.slave)) {
      ++seen;
      EXPECT_FALSE(o.alive);
      EXPECT_EQ(o.program, "picocom");
    }
  }
  EXPECT_EQ(seen, 2);
}
