#pragma once
// cncstreamd as an object: configuration in, everything built (file store,
// token, machines, jobs, API, HTTP server) on one io_context and a worker
// pool. main() runs it; the tests run it on a thread with port 0.
#include <boost/asio/io_context.hpp>
#include <boost/asio/thread_pool.hpp>

#include <memory>
#include <string>
#include <vector>

#include "cncstream/daemon/config.hpp"

namespace cncstream::daemon {

class Auth;
class FileStore;
class WsHub;
class Machines;
class JobManager;
class Api;
class HttpServer;
struct DaemonPendant;
class ShopLink;
class ShopWatch;

class Daemon {
 public:
  explicit Daemon(DaemonConfig config);  // throws std::runtime_error / std::invalid_argument naming what is wrong
  ~Daemon();
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  // Serves on the calling thread until stop().
  void run();
  void stop();  // any thread

  unsigned short port() const;
  const DaemonConfig& config() const { return config_; }
  const std::string& token() const;  // "" when none is required
  bool token_created() const { return token_created_; }
  boost::asio::io_context& io() { return io_; }
  JobManager& jobs() { return *jobs_; }
  Machines& machines() { return *machines_; }
  Api& api() { return *api_; }
  std::size_t pendant_count() const { return pendants_.size(); }
  ShopLink* shop() { return shop_.get(); }  // nullptr: not in a shop
  ShopWatch* shop_watch() { return shop_watch_.get(); }  // nullptr: not in a shop

 private:
  std::unique_ptr<DaemonPendant> start_pendant(const PendantSection& p);
  DaemonConfig config_;
  boost::asio::io_context io_;
  boost::asio::thread_pool pool_;
  bool token_created_ = false;
  std::unique_ptr<WsHub> hub_;
  std::unique_ptr<FileStore> files_;
  std::unique_ptr<Auth> auth_;
  std::unique_ptr<Machines> machines_;
  // After the machines: destroyed before them (a pendant drives a session).
  std::vector<std::unique_ptr<DaemonPendant>> pendants_;
  std::unique_ptr<JobManager> jobs_;
  std::unique_ptr<ShopLink> shop_;
  std::unique_ptr<ShopWatch> shop_watch_;  // reads through shop_'s view reader
  std::unique_ptr<Api> api_;
  std::unique_ptr<HttpServer> server_;
};

// The web page's folder: the config's, else <prefix>/share/cncstream/web
// beside the program, else the source tree's web/ (a build run from it).
std::filesystem::path find_web_root(const DaemonConfig& c);

// spdlog to stderr with sd-daemon priority prefixes ("<6>text"), which
// journald reads as the line's priority; no timestamps (journald adds them).
void setup_journald_logging();

}  // namespace cncstream::daemon
