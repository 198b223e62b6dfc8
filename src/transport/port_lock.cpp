#include "cncstream/transport/port_lock.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <pwd.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <mutex>
#include <sstream>
#include <system_error>
#include <thread>

namespace cncstream::transport {

namespace fs = std::filesystem;

namespace {

// The second line of the lock files we write: tells our own files (which
// are flock()ed while held) from other programs' (which are not).
constexpr const char* kMarker = "cncstream-lock 1";

std::mutex& identity_mutex() {
  static std::mutex m;
  return m;
}
LockIdentity& identity_storage() {
  static LockIdentity id;
  return id;
}

std::string own_program_name() {
  std::ifstream f("/proc/self/comm");
  std::string name;
  std::getline(f, name);
  return name.empty() ? std::string("cncstream") : name;
}

std::string errno_text(int e) { return std::generic_category().message(e); }

bool pid_alive(long pid) {
  if (pid <= 0) return false;
  // EPERM: it exists, owned by another user.
  return ::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM;
}

std::string proc_comm(long pid) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/comm");
  std::string name;
  std::getline(f, name);
  return name;
}

// Locks this process holds, removed by an atexit handler when the program
// ends through exit() without running the destructors. A forked child
// inherits the list but not the ownership: entries carry the owner's PID.
struct HeldEntry {
  fs::path file;
  dev_t dev;
  ino_t ino;
  pid_t pid;
};
// Never destroyed: the atexit handler runs after static destructors of
// objects made later than its registration, and must still find them.
std::mutex& held_mutex() {
  static auto* m = new std::mutex;
  return *m;
}
std::vector<HeldEntry>& held_list() {
  static auto* v = new std::vector<HeldEntry>;
  return *v;
}

bool same_file_at(const fs::path& file, dev_t dev, ino_t ino) {
  struct stat st {};
  return ::lstat(file.c_str(), &st) == 0 && st.st_dev == dev && st.st_ino == ino;
}

void remove_held_at_exit() {
  std::lock_guard<std::mutex> g(held_mutex());
  for (const auto& h : held_list())
    if (h.pid == ::getpid() && same_file_at(h.file, h.dev, h.ino)) ::unlink(h.file.c_str());
  held_list().clear();
}

void register_held(const fs::path& file, dev_t dev, ino_t ino) {
  std::lock_guard<std::mutex> g(held_mutex());
  static bool registered = false;
  // If it cannot be registered (no memory), a lock is still removed by its
  // destructor, and one left by exit() is found stale by its free flock.
  if (!registered) registered = std::atexit(remove_held_at_exit) == 0;
  held_list().push_back({file, dev, ino, ::getpid()});
}

void unregister_held(const fs::path& file) {
  std::lock_guard<std::mutex> g(held_mutex());
  auto& v = held_list();
  v.erase(std::remove_if(v.begin(), v.end(), [&](const HeldEntry& h) { return h.file == file && h.pid == ::getpid(); }),
          v.end());
}

// What a lock file says. `complete` is false for a file still being written
// (created, no PID yet).
struct LockInfo {
  PortOwner owner;
  bool ours = false;  // written by cncstream: held with flock() while live
  bool complete = false;
};

LockInfo read_lock(int fd, const fs::path& file) {
  LockInfo info;
  info.owner.lock_file = file;
  std::string text;
  char buf[512];
  ssize_t n = 0;
  ::lseek(fd, 0, SEEK_SET);
  while ((n = ::read(fd, buf, sizeof buf)) > 0 && text.size() < 4096) text.append(buf, static_cast<std::size_t>(n));
  struct stat st {};
  if (::fstat(fd, &st) == 0) info.owner.since = st.st_mtime;
  // Old-style binary lock files hold the PID as a 4-byte int.
  if (text.size() == 4 && !std::isdigit(static_cast<unsigned char>(text[0])) && text[0] != ' ') {
    int pid = 0;
    std::memcpy(&pid, text.data(), 4);
    info.owner.pid = pid;
    info.complete = true;
  } else {
    std::istringstream in(text);
    std::string first;
    if (std::getline(in, first) && !first.empty()) {
      std::istringstream f(first);
      long pid = 0;
      if (f >> pid) {
        info.owner.pid = pid;
        info.complete = true;
        f >> info.owner.program;  // minicom: "      1234 minicom user"
      }
    }
    std::string line;
    while (std::getline(in, line)) {
      if (line == kMarker) info.ours = true;
      else if (line.rfind("program=", 0) == 0) info.owner.program = line.substr(8);
      else if (line.rfind("api=", 0) == 0) info.owner.api = line.substr(4);
      else if (line.rfind("device=", 0) == 0) info.owner.device = line.substr(7);
      else if (line.rfind("since=", 0) == 0) {
        long long since = 0;
        const char* end = line.data() + line.size();
        if (const auto r = std::from_chars(line.data() + 6, end, since); r.ec == std::errc() && r.ptr == end)
          info.owner.since = static_cast<std::time_t>(since);
      }
    }
  }
  if (info.complete && info.owner.program.empty()) info.owner.program = proc_comm(info.owner.pid);
  info.owner.alive = pid_alive(info.owner.pid);
  // A live PID is not proof: PIDs are reused. Our own files are flock()ed by
  // their owner as long as it lives, so a free flock means the owner is gone.
  if (info.owner.alive && info.ours && ::flock(fd, LOCK_SH | LOCK_NB) == 0) {
    ::flock(fd, LOCK_UN);
    info.owner.alive = false;
  }
  return info;
}

std::optional<LockInfo> read_lock_file(const fs::path& file) {
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) return std::nullopt;
  LockInfo info = read_lock(fd, file);
  ::close(fd);
  return info;
}

bool writable_dir(const fs::path& d) { return ::access(d.c_str(), W_OK | X_OK) == 0; }

std::string format_since(std::time_t t) {
  std::tm then{}, today{};
  const std::time_t now = std::time(nullptr);
  ::localtime_r(&t, &then);
  ::localtime_r(&now, &today);
  const char* format = then.tm_year == today.tm_year && then.tm_yday == today.tm_yday ? "%H:%M" : "%Y-%m-%d %H:%M";
  char buf[64];
  return {buf, std::strftime(buf, sizeof buf, format, &then)};
}

std::string lock_content(const std::string& device) {
  const LockIdentity id = lock_identity();
  std::string program = id.program;
  for (char& c : program)
    if (std::isspace(static_cast<unsigned char>(c))) c = '_';
  std::string user = "?";
  passwd pw{};
  passwd* found = nullptr;
  std::array<char, 4096> pw_text{};
  if (::getpwuid_r(::getuid(), &pw, pw_text.data(), pw_text.size(), &found) == 0 && found) user = found->pw_name;
  // The first line is the UUCP/minicom form other programs parse: the PID in
  // ten columns, then the program and the user.
  std::string pid = std::to_string(static_cast<long>(::getpid()));
  std::string text(pid.size() < 10 ? 10 - pid.size() : 0, ' ');
  text.append(pid).append(" ").append(program).append(" ").append(user).append("\n");
  text.append(kMarker).append("\n");
  text.append("program=").append(program).append("\n");
  if (!id.api.empty()) text.append("api=").append(id.api).append("\n");
  text.append("device=").append(device).append("\n");
  text.append("since=").append(std::to_string(static_cast<long long>(std::time(nullptr)))).append("\n");
  return text;
}

}  // namespace

void set_lock_identity(LockIdentity id) {
  std::lock_guard<std::mutex> g(identity_mutex());
  identity_storage() = std::move(id);
}

LockIdentity lock_identity() {
  std::lock_guard<std::mutex> g(identity_mutex());
  LockIdentity id = identity_storage();
  if (id.program.empty()) id.program = own_program_name();
  return id;
}

std::string PortOwner::describe() const {
  std::string s = program.empty() ? std::string("another process") : program;
  if (pid > 0) {
    s += " (pid " + std::to_string(pid);
    if (!api.empty()) s.append(", API ").append(api);
    if (!alive) s += ", no longer running";
    s += ")";
  } else if (lock_file.empty()) {
    s += " (TIOCEXCL)";
  }
  if (since) s.append(" since ").append(format_since(*since));
  return s;
}

std::string resolve_device(const std::string& path) {
  std::error_code ec;
  const fs::path real = fs::canonical(path, ec);
  return ec ? path : real.string();
}

std::string lock_file_name(const std::string& device) {
  std::string rest = device;
  if (rest.rfind("/dev/", 0) == 0) rest = rest.substr(5);
  while (!rest.empty() && rest.front() == '/') rest.erase(0, 1);
  std::replace(rest.begin(), rest.end(), '/', '_');
  return "LCK.." + rest;
}

std::vector<fs::path> lock_dirs() {
  if (const char* env = std::getenv("CNCSTREAM_LOCK_DIR"); env && *env) return {fs::path(env)};
  std::vector<fs::path> dirs;
  std::error_code ec;
  if (fs::is_directory("/run/lock", ec)) dirs.emplace_back("/run/lock");
  else if (fs::is_directory("/var/lock", ec)) dirs.emplace_back("/var/lock");
  if (const char* xdg = std::getenv("XDG_RUNTIME_DIR"); xdg && *xdg) dirs.push_back(fs::path(xdg) / "cncstream");
  return dirs;
}

std::optional<PortOwner> port_owner(const std::string& path) {
  const std::string device = resolve_device(path);
  const std::string name = lock_file_name(device);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
  for (const auto& dir : lock_dirs()) {
    for (;;) {
      const auto info = read_lock_file(dir / name);
      if (!info) break;
      // A file just created and not yet written: give its writer a moment.
      if (!info->complete && std::chrono::steady_clock::now() < deadline) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        continue;
      }
      if (info->complete && info->owner.alive) {
        PortOwner o = info->owner;
        o.device = device;
        return o;
      }
      break;
    }
  }
  return std::nullopt;
}

std::vector<PortOwner> list_port_owners() {
  std::vector<PortOwner> out;
  for (const auto& dir : lock_dirs()) {
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("LCK..", 0) != 0) continue;
      const auto info = read_lock_file(entry.path());
      if (!info || !info->complete) continue;
      PortOwner o = info->owner;
      if (o.device.empty()) {
        std::string dev = name.substr(5);
        // Our own names turn '/' into '_' under /dev/; "pts_3" was /dev/pts/3.
        if (dev.rfind("pts_", 0) == 0) dev[3] = '/';
        o.device = "/dev/" + dev;
      }
      out.push_back(std::move(o));
    }
  }
  std::sort(out.begin(), out.end(), [](const PortOwner& a, const PortOwner& b) { return a.device < b.device; });
  return out;
}

std::vector<PortOwner> processes_using(const std::string& device) {
  std::vector<PortOwner> out;
  const std::string real = resolve_device(device);
  std::error_code ec;
  for (const auto& proc : fs::directory_iterator("/proc", ec)) {
    const std::string pid_text = proc.path().filename().string();
    long pid = 0;
    const char* end = pid_text.data() + pid_text.size();
    if (const auto r = std::from_chars(pid_text.data(), end, pid); r.ec != std::errc() || r.ptr != end) continue;
    std::error_code fec;
    for (const auto& fd : fs::directory_iterator(proc.path() / "fd", fec)) {
      std::error_code lec;
      if (fs::read_symlink(fd.path(), lec).string() != real) continue;
      PortOwner o;
      o.device = real;
      o.pid = pid;
      o.program = proc_comm(o.pid);
      out.push_back(std::move(o));
      break;
    }
  }
  return out;
}

std::string busy_message(const std::string& path, const PortOwner& owner) {
  std::string m = "cannot open " + path;
  if (!owner.device.empty() && owner.device != path) m.append(" (").append(owner.device).append(")");
  m.append(": it is in use by ").append(owner.describe());
  if (!owner.lock_file.empty()) m.append("; lock file ").append(owner.lock_file.string());
  return m;
}

// ---- PortLock ---------------------------------------------------------------

PortLock::~PortLock() { release(); }

PortLock::PortLock(PortLock&& o) noexcept
    : fd_(o.fd_), file_(std::move(o.file_)), device_(std::move(o.device_)), note_(std::move(o.note_)), dev_(o.dev_),
      ino_(o.ino_) {
  o.fd_ = -1;
}

PortLock& PortLock::operator=(PortLock&& o) noexcept {
  if (this != &o) {
    release();
    fd_ = o.fd_;
    file_ = std::move(o.file_);
    device_ = std::move(o.device_);
    note_ = std::move(o.note_);
    dev_ = o.dev_;
    ino_ = o.ino_;
    o.fd_ = -1;
  }
  return *this;
}

void PortLock::release() {
  if (fd_ < 0) return;
  // Remove the file only if it is still ours (nobody may replace a live,
  // flock()ed lock, but be sure before unlinking a name).
  if (same_file_at(file_, dev_, ino_)) ::unlink(file_.c_str());
  unregister_held(file_);
  ::close(fd_);  // drops the flock
  fd_ = -1;
}

PortLock PortLock::acquire(const std::string& path) {
  PortLock lock;
  lock.device_ = resolve_device(path);
  const std::string name = lock_file_name(lock.device_);
  const auto dirs = lock_dirs();
  const bool env_dir = std::getenv("CNCSTREAM_LOCK_DIR") && *std::getenv("CNCSTREAM_LOCK_DIR");

  // The folder new locks go to: the first writable one (the private fallback
  // and $CNCSTREAM_LOCK_DIR are made when missing).
  std::optional<fs::path> target;
  for (std::size_t i = 0; i < dirs.size() && !target; ++i) {
    const bool shared = !env_dir && i == 0 && (dirs[i] == "/run/lock" || dirs[i] == "/var/lock");
    if (!shared) {
      std::error_code ec;
      fs::create_directories(dirs[i], ec);
      if (!ec && !env_dir) fs::permissions(dirs[i], fs::perms::owner_all, fs::perm_options::replace, ec);
    }
    if (writable_dir(dirs[i])) {
      target = dirs[i];
      if (!shared && !env_dir && i > 0)
        lock.note_ = "lock file in " + dirs[i].string() + " (" + dirs[0].string() +
                     " is not writable for this user): only this user's programs see it; TIOCEXCL keeps others out";
    }
  }
  if (!target) {
    lock.note_ = "no lock file for " + path + ": no writable lock folder (" +
                 (dirs.empty() ? std::string("none; set XDG_RUNTIME_DIR") : dirs[0].string() + " is not writable") +
                 "); the port is held through TIOCEXCL only";
    return lock;
  }

  auto add_note = [&lock](const std::string& s) {
    if (!lock.note_.empty()) lock.note_ += "; ";
    lock.note_ += s;
  };
  const fs::path file = *target / name;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(1);
  for (;;) {
    // A live lock in another folder (another user's fallback, or ours) wins too.
    for (const auto& d : dirs) {
      if (d == *target) continue;
      if (auto info = read_lock_file(d / name); info && info->complete && info->owner.alive) {
        info->owner.device = lock.device_;
        throw PortBusyError(busy_message(path, info->owner), info->owner);
      }
    }
    const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0644);
    if (fd >= 0) {
      // Locked before anything is written: a reader sees either an empty
      // (being written) file or a complete one that is already flock()ed.
      ::flock(fd, LOCK_EX);
      const std::string text = lock_content(lock.device_);
      const bool written = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
      ::fchmod(fd, 0644);  // readable by all whatever the umask: others must see who owns the port
      struct stat st {};
      if (!written || ::fstat(fd, &st) != 0) {
        const int e = errno;
        ::unlink(file.c_str());
        ::close(fd);
        throw std::runtime_error("cannot write lock file " + file.string() + ": " + errno_text(e));
      }
      lock.fd_ = fd;
      lock.file_ = file;
      lock.dev_ = st.st_dev;
      lock.ino_ = st.st_ino;
      register_held(file, st.st_dev, st.st_ino);
      return lock;
    }
    if (errno != EEXIST) {
      add_note("no lock file for " + path + ": cannot create " + file.string() + ": " + errno_text(errno) +
               "; the port is held through TIOCEXCL only");
      return lock;
    }
    const int ofd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
    if (ofd < 0) continue;  // removed meanwhile: try again
    LockInfo info = read_lock(ofd, file);
    info.owner.device = lock.device_;
    const bool late = std::chrono::steady_clock::now() >= deadline;
    if (!info.complete && !late) {
      ::close(ofd);
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      continue;
    }
    if ((info.complete && info.owner.alive) || late) {
      ::close(ofd);
      throw PortBusyError(busy_message(path, info.owner), info.owner);
    }
    // Stale. Take its flock before removing it, and check the name still
    // means this file: two programs taking over one stale lock must not
    // remove each other's fresh one.
    if (::flock(ofd, LOCK_EX | LOCK_NB) == 0) {
      struct stat st {};
      if (::fstat(ofd, &st) == 0 && same_file_at(file, st.st_dev, st.st_ino)) {
        if (::unlink(file.c_str()) == 0) {
          add_note("removed the stale lock file " + file.string() + " of " + info.owner.describe());
        } else if (errno == EACCES || errno == EPERM) {
          // Another user's file in the sticky /run/lock.
          const int e = errno;
          ::close(ofd);
          throw std::runtime_error("cannot open " + path + ": the lock file " + file.string() + " of " +
                                   info.owner.describe() + " is stale but cannot be removed (" + errno_text(e) +
                                   "): remove it by hand");
        }
      }
    }
    ::close(ofd);
    if (std::chrono::steady_clock::now() >= deadline)
      throw std::runtime_error("cannot open " + path + ": could not take the lock file " + file.string() +
                               " within 1 s (other programs are contending for it)");
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

}  // namespace cncstream::transport
