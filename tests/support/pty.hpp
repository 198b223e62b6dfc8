#pragma once
// A pseudo-terminal pair for tests that open a "serial port" (the slave):
// shared by the transport and app tests. Header only: tests/support holds no
// .cpp, so it is no test area of its own.
#include <fcntl.h>
#include <stdlib.h>
#include <unistd.h>

#include <stdexcept>
#include <string>

namespace test_support {

struct Pty {
  Pty() {
    master = ::posix_openpt(O_RDWR | O_NOCTTY);
    if (master < 0 || ::grantpt(master) != 0 || ::unlockpt(master) != 0) throw std::runtime_error("no pty");
    slave = ::ptsname(master);
  }
  ~Pty() { ::close(master); }
  Pty(const Pty&) = delete;
  Pty& operator=(const Pty&) = delete;
  int master = -1;
  std::string slave;
};

}  // namespace test_support
