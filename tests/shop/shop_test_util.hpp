#pragma once
// A throw-away PostgreSQL for the shop's tests: a cluster initialised once
// per build folder (initdb, as a user that is not root when the tests run as
// root: initdb and postgres refuse root), copied into a temporary folder per
// test and served on 127.0.0.1 and a free port; stopped and removed after.
// Tests call GTEST_SKIP when the binaries are missing (scripts/setup.sh
// installs them).
#include <fcntl.h>
#include <grp.h>
#include <netinet/in.h>
#include <pwd.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "cncstream/shop/pg.hpp"

namespace shoptest {

namespace fs = std::filesystem;

inline unsigned short free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = 0;
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t n = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &n);
  ::close(fd);
  return ntohs(a.sin_port);
}

inline fs::path temp_dir(const std::string& tag) {
  std::random_device rd;
  const fs::path p = fs::temp_directory_path() / ("cncstream-shop-" + tag + "-" + std::to_string(::getpid()) + "-" +
                                                  std::to_string(rd()));
  fs::create_directories(p);
  return p;
}

// A program on PATH, else in one of `dirs`; "" when absent.
inline std::string find_program(const std::string& name, const std::vector<fs::path>& dirs = {}) {
  if (const char* path = std::getenv("PATH")) {
    std::string all = path;
    std::size_t start = 0;
    while (start <= all.size()) {
      const auto end = all.find(':', start);
      const fs::path p = fs::path(all.substr(start, end == std::string::npos ? std::string::npos : end - start)) / name;
      if (::access(p.c_str(), X_OK) == 0) return p.string();
      if (end == std::string::npos) break;
      start = end + 1;
    }
  }
  for (const auto& d : dirs)
    if (::access((d / name).c_str(), X_OK) == 0) return (d / name).string();
  return {};
}

inline std::vector<fs::path> postgres_bin_dirs() {
  std::vector<fs::path> dirs;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator("/usr/lib/postgresql", ec)) dirs.push_back(e.path() / "bin");
  std::sort(dirs.rbegin(), dirs.rend());  // the newest first
  return dirs;
}

// Whom the server runs as: ourselves, or (as root) postgres, else nobody.
struct RunAs {
  bool switch_user = false;
  uid_t uid = 0;
  gid_t gid = 0;
};
inline RunAs server_user() {
  RunAs r;
  if (::geteuid() != 0) return r;
  for (const char* name : {"postgres", "nobody"})
    if (const passwd* pw = ::getpwnam(name)) {
      r.switch_user = true;
      r.uid = pw->pw_uid;
      r.gid = pw->pw_gid;
      return r;
    }
  throw std::runtime_error("running as root and neither 'postgres' nor 'nobody' exists to run PostgreSQL as");
}

inline void chown_tree(const fs::path& p, const RunAs& u) {
  if (!u.switch_user) return;
  ::chown(p.c_str(), u.uid, u.gid);
  for (const auto& e : fs::recursive_directory_iterator(p)) ::lchown(e.path().c_str(), u.uid, u.gid);
}

// Starts `argv` as `u` with stdout/stderr to `log`; returns the pid.
inline pid_t spawn(const std::vector<std::string>& argv, const RunAs& u, const fs::path& log) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd >= 0) {
      ::dup2(fd, 1);
      ::dup2(fd, 2);
    }
    if (u.switch_user) {
      ::setgroups(0, nullptr);
      if (::setgid(u.gid) != 0 || ::setuid(u.uid) != 0) ::_exit(126);
    }
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execv(args[0], args.data());
    ::_exit(127);
  }
  return pid;
}

inline int run(const std::vector<std::string>& argv, const RunAs& u, const fs::path& log) {
  const pid_t pid = spawn(argv, u, log);
  int st = 0;
  ::waitpid(pid, &st, 0);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

class TempPostgres {
 public:
  static std::string initdb() { return find_program("initdb", postgres_bin_dirs()); }
  static std::string postgres() { return find_program("postgres", postgres_bin_dirs()); }
  static bool available() { return !initdb().empty() && !postgres().empty(); }

  TempPostgres() : user_(server_user()) {
    dir_ = temp_dir("pg");
    chown_dir(dir_);
    data_ = dir_ / "data";
    copy_template();
    port_ = free_port();
    start();
  }
  ~TempPostgres() {
    stop();
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  TempPostgres(const TempPostgres&) = delete;
  TempPostgres& operator=(const TempPostgres&) = delete;

  unsigned short port() const { return port_; }
  std::string url(const std::string& db = "postgres", const std::string& user = "postgres") const {
    return "postgresql://" + user + "@127.0.0.1:" + std::to_string(port_) + "/" + db;
  }
  bool running() const { return pid_ > 0; }

  void start() {
    if (pid_ > 0) return;
    pid_ = spawn({postgres(), "-D", data_.string(), "-p", std::to_string(port_), "-k", dir_.string(), "-c",
                  "listen_addresses=127.0.0.1", "-c", "fsync=off", "-c", "synchronous_commit=off", "-c",
                  "full_page_writes=off", "-c", "max_connections=60", "-c", "shared_buffers=16MB"},
                 user_, dir_ / "server.log");
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (std::chrono::steady_clock::now() < end) {
      try {
        cncstream::shop::PgConnection c(url());
        return;
      } catch (const cncstream::shop::ShopError&) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
    }
    throw std::runtime_error("PostgreSQL did not start: see " + (dir_ / "server.log").string());
  }
  // Fast shutdown: clients are disconnected at once.
  void stop() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGINT);
    int st = 0;
    ::waitpid(pid_, &st, 0);
    pid_ = -1;
  }

  // A fresh database with the shop's schema (migrated by the caller) in it.
  std::string create_database(const std::string& name) {
    cncstream::shop::PgConnection c(url());
    c.exec("CREATE DATABASE " + name);
    return url(name);
  }

 private:
  void chown_dir(const fs::path& p) const {
    if (user_.switch_user) ::chown(p.c_str(), user_.uid, user_.gid);
  }
  // The cluster is initialised once per build folder (initdb takes seconds)
  // and copied for each test; a lock keeps parallel tests from racing.
  void copy_template() {
    const fs::path tmpl = fs::path(CNCSTREAM_BINARY_DIR) / "shop-pg-template";
    const fs::path lock = fs::path(CNCSTREAM_BINARY_DIR) / "shop-pg-template.lock";
    const int fd = ::open(lock.c_str(), O_RDWR | O_CREAT, 0644);
    ::flock(fd, LOCK_EX);
    if (!fs::exists(tmpl / "PG_VERSION")) {
      const fs::path work = fs::path(CNCSTREAM_BINARY_DIR) / "shop-pg-template.new";
      std::error_code ec;
      fs::remove_all(work, ec);
      fs::create_directories(work);
      chown_dir(work);
      const int rc = run({initdb(), "-D", work.string(), "-U", "postgres", "--auth=trust", "-E", "UTF8",
                          "--no-sync", "--locale=C"},
                         user_, dir_ / "initdb.log");
      if (rc != 0) {
        ::close(fd);
        throw std::runtime_error("initdb failed (" + std::to_string(rc) + "): see " + (dir_ / "initdb.log").string());
      }
      fs::remove_all(tmpl, ec);
      fs::rename(work, tmpl);
    }
    fs::copy(tmpl, data_, fs::copy_options::recursive);
    ::close(fd);
    fs::permissions(data_, fs::perms::owner_all, fs::perm_options::replace);
    chown_tree(data_, user_);
  }

  RunAs user_;
  fs::path dir_, data_;
  unsigned short port_ = 0;
  pid_t pid_ = -1;
};

#define SHOP_REQUIRE_POSTGRES()                                                                                  \
  do {                                                                                                           \
    if (!shoptest::TempPostgres::available())                                                                    \
      GTEST_SKIP() << "PostgreSQL's initdb/postgres are not installed (scripts/setup.sh installs postgresql)";  \
  } while (0)

}  // namespace shoptest
