#pragma once
// One owner per serial port. Two programs polling one controller interleave
// their status queries and steal each other's answers, so whoever opens a
// device takes (a) a UUCP-style lock file, `LCK..ttyUSB0` in /run/lock, the
// convention minicom, picocom and ModemManager-aware tools honour, holding
// the owner's PID, program and (for the daemon) its API address, created with
// O_EXCL and held with flock(); and (b) TIOCEXCL on the open tty (see
// serial_transport.cpp), so the kernel refuses even programs that ignore lock
// files. Symlinks (/dev/serial/by-id/...) are resolved first: two names of
// one port share one lock.
//
// Where lock files go: $CNCSTREAM_LOCK_DIR when set (tests, unusual setups),
// else /run/lock (or /var/lock), else, when that is not writable for this
// user, $XDG_RUNTIME_DIR/cncstream (seen only by this user's programs; the
// note says so). Readers look in all of them.
#include <sys/types.h>

#include <ctime>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace cncstream::transport {

// Who this process is, as written into the lock files it takes. The program
// defaults to this process's name; the daemon sets its API address so that a
// CLI finding the port taken can hand its job over.
struct LockIdentity {
  std::string program;
  std::string api;  // "http://127.0.0.1:8420", or empty
};
void set_lock_identity(LockIdentity id);
LockIdentity lock_identity();

// The owner of a port as its lock file (or the kernel) tells it.
struct PortOwner {
  std::string device;               // the resolved device, "/dev/ttyUSB0"
  std::filesystem::path lock_file;  // empty when found through TIOCEXCL alone
  long pid = 0;
  std::string program;              // "cncstreamd", "minicom"; empty when unknown
  std::string api;                  // the daemon's API address; empty otherwise
  std::optional<std::time_t> since;
  bool alive = true;                // false: a stale lock of a dead process
  // "cncstreamd (pid 1234, API http://127.0.0.1:8420) since 10:31"
  std::string describe() const;
};

// The real device behind a name (symlinks resolved); the name itself when it
// does not exist.
std::string resolve_device(const std::string& path);
// "LCK..ttyUSB0" for /dev/ttyUSB0; "LCK..pts_3" for /dev/pts/3.
std::string lock_file_name(const std::string& device);
// The folders lock files may be in, the one new locks go to first.
std::vector<std::filesystem::path> lock_dirs();

// Who holds `path` now: a live lock file in any lock folder (nullopt when
// none; stale locks are not owners).
std::optional<PortOwner> port_owner(const std::string& path);
// Every lock file in the lock folders, live and stale (for `cncstream status`).
std::vector<PortOwner> list_port_owners();
// Processes that have `device` open, from /proc (only those this user may
// inspect): who to name when TIOCEXCL refuses us and no lock file says.
std::vector<PortOwner> processes_using(const std::string& device);

// The port is taken; what() is the operator's message naming the owner.
class PortBusyError : public std::runtime_error {
 public:
  PortBusyError(const std::string& message, PortOwner owner)
      : std::runtime_error(message), owner_(std::move(owner)) {}
  const PortOwner& owner() const { return owner_; }

 private:
  PortOwner owner_;
};

// "cannot open /dev/ttyUSB0: it is in use by cncstreamd (pid 1234, API ...) since 10:31"
std::string busy_message(const std::string& path, const PortOwner& owner);

// A held lock file; released (flock dropped, file removed) on destruction,
// release(), or at process exit.
class PortLock {
 public:
  PortLock() = default;
  ~PortLock();
  PortLock(PortLock&& other) noexcept;
  PortLock& operator=(PortLock&& other) noexcept;
  PortLock(const PortLock&) = delete;
  PortLock& operator=(const PortLock&) = delete;

  // Takes the lock for `path`. Throws PortBusyError when a live process holds
  // it; removes a stale lock of a dead process (saying so in note()). When no
  // lock folder is writable the port is still held through TIOCEXCL: the
  // returned lock holds nothing and note() says why.
  static PortLock acquire(const std::string& path);

  void release();
  bool held() const { return fd_ >= 0; }
  const std::filesystem::path& file() const { return file_; }
  const std::string& device() const { return device_; }
  // What the operator should know: a stale lock taken over, a fallback folder.
  const std::string& note() const { return note_; }

 private:
  int fd_ = -1;
  std::filesystem::path file_;
  std::string device_;
  std::string note_;
  dev_t dev_ = 0;
  ino_t ino_ = 0;
};

}  // namespace cncstream::transport
