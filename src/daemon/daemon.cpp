#include "cncstream/daemon/daemon.hpp"

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/post.hpp>
#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <latch>
#include <thread>

#include "cncstream/daemon/api.hpp"
#include "cncstream/daemon/auth.hpp"
#include "cncstream/daemon/file_store.hpp"
#include "cncstream/daemon/http_server.hpp"
#include "cncstream/daemon/job_manager.hpp"
#include "cncstream/daemon/machines.hpp"
#include "cncstream/daemon/shop_link.hpp"
#include "cncstream/daemon/shop_watch.hpp"
#include "cncstream/daemon/ws_hub.hpp"
#include "cncstream/pendant/pendant_controller.hpp"
#include "cncstream/pendant/pendant_usb.hpp"
#include "cncstream/pendant/usb_pendant_reader.hpp"
#include "cncstream/transport/journal.hpp"
#include "cncstream/transport/port_lock.hpp"

#ifndef CNCSTREAM_SOURCE_WEB_DIR
#define CNCSTREAM_SOURCE_WEB_DIR ""
#endif

namespace cncstream::daemon {

namespace fs = std::filesystem;

namespace {

unsigned worker_count(const DaemonConfig& c) {
  if (c.limits.worker_threads) return c.limits.worker_threads;
  return std::max(1u, std::thread::hardware_concurrency());
}

// sd-daemon(3) priorities: <3> error, <4> warning, <6> info, <7> debug.
class PriorityFlag : public spdlog::custom_flag_formatter {
 public:
  void format(const spdlog::details::log_msg& msg, const std::tm&, spdlog::memory_buf_t& dest) override {
    const char* p = "<6>";
    switch (msg.level) {
      case spdlog::level::critical: p = "<2>"; break;
      case spdlog::level::err: p = "<3>"; break;
      case spdlog::level::warn: p = "<4>"; break;
      case spdlog::level::debug:
      case spdlog::level::trace: p = "<7>"; break;
      default: break;
    }
    dest.append(p, p + 3);
  }
  std::unique_ptr<custom_flag_formatter> clone() const override { return spdlog::details::make_unique<PriorityFlag>(); }
};

}  // namespace

void setup_journald_logging() {
  auto logger = std::make_shared<spdlog::logger>("cncstreamd", std::make_shared<spdlog::sinks::stderr_sink_mt>());
  auto f = std::make_unique<spdlog::pattern_formatter>();
  f->add_flag<PriorityFlag>('*').set_pattern("%*%v");
  logger->set_formatter(std::move(f));
  logger->flush_on(spdlog::level::info);
  spdlog::set_default_logger(logger);
}

fs::path find_web_root(const DaemonConfig& c) {
  if (!c.web_root.empty()) return c.web_root;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    fs::path installed = exe.parent_path().parent_path() / "share" / "cncstream" / "web";
    if (fs::is_directory(installed, ec)) return installed;
  }
  fs::path source = CNCSTREAM_SOURCE_WEB_DIR;
  if (!source.empty() && fs::is_directory(source, ec)) return source;
  return {};
}

// A WHB04B pendant on one machine: its USB receiver, the controller that
// turns its keys and wheel into that machine's session commands, and the
// reader thread between them (destroyed in that reverse order).
struct DaemonPendant {
  std::unique_ptr<pendant::PendantUsb> usb;
  std::unique_ptr<pendant::PendantController> controller;
  std::unique_ptr<pendant::UsbPendantReader> reader;
  ~DaemonPendant() {
    reader.reset();
    controller.reset();
    usb.reset();
  }
};

std::unique_ptr<DaemonPendant> Daemon::start_pendant(const PendantSection& p) {
  Machine* m = machines_->find(p.machine);
  if (!m || !m->session) throw std::invalid_argument("pendant: no machine named '" + p.machine + "'");
  pendant::PendantConfig pc;
  pc.lease_s = p.lease_s;
  pc.macros = pendant::default_macros();
  for (const auto& text : p.macros) {
    auto [n, action] = pendant::parse_macro_option(text);
    pc.macros[n] = action;
  }
  auto d = std::make_unique<DaemonPendant>();
  d->usb = pendant::make_libusb_pendant();  // throws naming libusb's error
  d->controller = std::make_unique<pendant::PendantController>(*m->session, pc);
  const std::string name = p.machine;
  d->controller->set_log([name](pendant::LogLevel level, const std::string& text) {
    if (level == pendant::LogLevel::Warning) spdlog::warn("pendant ({}): {}", name, text);
    else if (level == pendant::LogLevel::Info) spdlog::info("pendant ({}): {}", name, text);
  });
  d->reader = std::make_unique<pendant::UsbPendantReader>(*d->usb, *d->controller);
  spdlog::info("pendant: a WHB04B receiver (10ce:eb93) drives machine '{}' when plugged in", p.machine);
  return d;
}

Daemon::Daemon(DaemonConfig config) : config_(std::move(config)), pool_(worker_count(config_)) {
  validate(config_);
  // The workers (tool paths, uploads, verifies) run at a lower priority than
  // the event loop, so status keeps flowing while a big part is computed;
  // threads they start (oneTBB's) inherit it. One task per thread: each
  // waits until all have started, so every thread runs exactly one.
  {
    const unsigned n = worker_count(config_);
    // Shared: a task may still be returning from its wait when ours ends.
    auto started = std::make_shared<std::latch>(static_cast<std::ptrdiff_t>(n));
    for (unsigned i = 0; i < n; ++i)
      boost::asio::post(pool_, [started] {
        ::setpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)), 10);
        started->arrive_and_wait();
      });
    started->wait();
  }
  // The journal first: where it goes depends on whether data_dir was given.
  config_.journal = journal_path(config_);
  const fs::path journal = config_.journal;
  if (config_.data_dir.empty()) config_.data_dir = default_data_dir();
  fs::create_directories(config_.data_dir);
  std::string token;
  if (config_.token_required()) {
    token = load_or_create_token(config_.data_dir, token_created_);
    if (token_created_)
      spdlog::warn("a token was generated (shown once; also in {}): {}", (config_.data_dir / "token").string(), token);
    else
      spdlog::info("clients need the token in {}", (config_.data_dir / "token").string());
  }
  hub_ = std::make_unique<WsHub>(config_.limits.max_ws_clients, config_.limits.ws_queue_messages);
  files_ = std::make_unique<FileStore>(config_.data_dir / "files");
  auth_ = std::make_unique<Auth>(config_, token);
  machines_ = std::make_unique<Machines>(io_, pool_, config_, *hub_, journal);
  for (const auto& p : config_.pendants) {
    // A pendant that cannot work (no libusb) is said loudly, but the
    // machines and the API still serve: nothing moves because of it.
    try {
      pendants_.push_back(start_pendant(p));
    } catch (const std::runtime_error& e) {
      spdlog::error("pendant for machine '{}' not started: {}", p.machine, e.what());
    }
  }
  jobs_ = std::make_unique<JobManager>(io_, pool_, config_, *files_, *machines_, *hub_, journal,
                                       config_.data_dir / "programs");
  jobs_->recover();
  // A shop's member: its events go to the hub through the journal's outbox.
  if (!config_.shop.url.empty()) {
    shop_ = std::make_unique<ShopLink>(io_, config_, *files_, *machines_, *jobs_);
    // The hub's wake-ups push the shop view to the WebSocket clients.
    shop_watch_ = std::make_unique<ShopWatch>(io_, shop_->view(), *hub_, config_.shop.url,
                                              config_.shop.watch_min_interval_s);
  }
  const fs::path web = find_web_root(config_);
  if (web.empty()) spdlog::warn("no web page folder found (set web.root): GET / answers 404");
  api_ = std::make_unique<Api>(io_, pool_, config_, *auth_, *files_, *machines_, *jobs_, *hub_, web, shop_.get());
  server_ = std::make_unique<HttpServer>(io_, config_, *api_, *files_);
  server_->start();
  spdlog::info("listening on {}:{} ({}), data in {}, journal {}, {} machine(s)", config_.listen_address, port(),
               config_.token_required() ? "token required" : "loopback, no token", config_.data_dir.string(),
               journal.string(), config_.machines.size());
  // The lock files of the machines' ports name this daemon and its API, so a
  // `cncstream FILE PORT` finding the port taken hands its job over here. A
  // wildcard listen address is reached locally through loopback.
  std::string api_host = config_.listen_address;
  if (api_host == "0.0.0.0" || api_host.empty()) api_host = "127.0.0.1";
  else if (api_host == "::") api_host = "::1";
  if (api_host.find(':') != std::string::npos) api_host = "[" + api_host + "]";
  std::string api = "http://";
  api.append(api_host).append(":").append(std::to_string(port()));
  transport::set_lock_identity({"cncstreamd", api});
  machines_->open_all();
}

Daemon::~Daemon() {
  stop();
  // Generation tasks see their stop request at the next checkpoint; the
  // pool is joined before the objects its tasks use go away.
  jobs_->stop_generations();
  pool_.join();
  shop_watch_.reset();  // before the view reader it reads through
  shop_.reset();        // before the jobs and machines it reports
  jobs_.reset();
  server_.reset();
  api_.reset();
  pendants_.clear();  // the pendants drive the machines' sessions
  machines_.reset();
}

void Daemon::run() {
  auto guard = boost::asio::make_work_guard(io_);
  io_.run();
}

void Daemon::stop() {
  boost::asio::post(io_, [this] {
    if (server_) server_->stop();
    io_.stop();
  });
}

unsigned short Daemon::port() const { return server_ ? server_->port() : 0; }

const std::string& Daemon::token() const { return auth_->token(); }

}  // namespace cncstream::daemon
