#pragma once
// What a machine session opens: a serial device by path, or the in-process
// simulator (a pseudo-terminal served by a thread of this process). The
// session asks for the path at each (re)connection and says when it has
// the port open, which is when a simulator starts serving (so its power-on
// banner reaches the host like a DTR reset's).
#include <string>

namespace cncstream::session {

class MachinePort {
 public:
  virtual ~MachinePort() = default;
  virtual std::string path() = 0;
  virtual void opened() {}
  virtual std::string describe() { return path(); }
};

class DevicePort final : public MachinePort {
 public:
  explicit DevicePort(std::string path) : path_(std::move(path)) {}
  std::string path() override { return path_; }

 private:
  std::string path_;
};

}  // namespace cncstream::session
