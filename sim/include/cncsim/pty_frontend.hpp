#pragma once
// The simulator as a serial port: a pseudo-terminal whose slave side a host
// opens like /dev/ttyUSB0. Everything the host writes is read at once and fed
// to the machine, which drops what does not fit its 128-byte RX buffer,
// exactly as the firmware would with a careless host.
#include <atomic>
#include <filesystem>
#include <optional>
#include <string>

#include "cncsim/machine.hpp"

namespace cncsim {

struct PtyOptions {
  std::optional<std::filesystem::path> link;  // symlink to the slave path
  double speed = 1.0;  // virtual seconds per wall second; <= 0 means "max"
};

class PtyError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class PtyFrontEnd {
 public:
  PtyFrontEnd(Machine& machine, PtyOptions options);
  ~PtyFrontEnd();
  PtyFrontEnd(const PtyFrontEnd&) = delete;
  PtyFrontEnd& operator=(const PtyFrontEnd&) = delete;

  const std::string& slave_path() const { return slave_path_; }

  enum class Exit { Stopped, Vanished };
  // Serves until `stop` becomes true or the machine vanishes (then the pty
  // is closed so the host sees the port go away). RxOverflowError (strict)
  // propagates to the caller.
  Exit run(const std::atomic<bool>& stop);

 private:
  void flush_output();
  void close_all();
  void watch_host();

  Machine& machine_;
  PtyOptions options_;
  int master_ = -1;
  int slave_keepalive_ = -1;  // keeps the master readable while no host is attached
  // A host's exclusive mode (TIOCEXCL) would outlive it here, since this end
  // keeps the pty open: a host killed mid-job could never clear it and the
  // next one would get EBUSY. A real serial port forgets it at its last
  // close, so the front end watches the slave's opens and closes (inotify)
  // and clears it when the last host has gone.
  int host_watch_ = -1;
  int host_opens_ = 0;
  std::string slave_path_;
  std::string pending_out_;
};

}  // namespace cncsim
