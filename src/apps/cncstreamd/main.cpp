// cncstreamd: the machine-side daemon (docs/daemon.md, docs/api-v1.md).
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <csignal>
#include <iostream>
#include <thread>

#include "cncstream/daemon/config.hpp"
#include "cncstream/daemon/daemon.hpp"

namespace {
cncstream::daemon::Daemon* g_daemon = nullptr;
}

namespace {

int run_daemon(int argc, char** argv) {
  using namespace cncstream::daemon;
  CLI::App app{"cncstreamd: serves CNC machines over HTTP and WebSocket (API: docs/api-v1.md)"};
  std::string config_file, listen, data, shop;
  std::vector<std::string> machines;
  bool verbose = false;
  app.add_option("--config", config_file, "TOML configuration file");
  app.add_option("--listen", listen, "ADDR:PORT (default 127.0.0.1:8420; anything but loopback requires the token)");
  app.add_option("--data", data, "Data folder (uploads, programs, token)");
  app.add_option("--machine", machines, "NAME=PORT[,profile=P,baud=B,sim_speed=S] (replaces the file's machines)");
  app.add_option("--shop", shop, "Join a shop: the hub's postgresql:// URL (docs/shop.md)");
  app.add_flag("-v,--verbose", verbose, "Log requests that fail on the wire (debug level)");
  CLI11_PARSE(app, argc, argv);
  setup_journald_logging();
  if (verbose) spdlog::set_level(spdlog::level::debug);
  try {
    // (Not a conditional expression: GCC 12 at -O1 with ASan then warns of
    // an uninitialised temporary.)
    DaemonConfig c;
    if (!config_file.empty()) c = load_config(config_file);
    if (!listen.empty()) apply_listen(c, listen);
    if (!data.empty()) c.data_dir = data;
    if (!shop.empty()) c.shop.url = shop;
    if (!machines.empty()) {
      c.machines.clear();
      for (const auto& m : machines) c.machines.push_back(parse_machine_option(m));
    }
    validate(c);
    // SIGINT/SIGTERM end the loop; the sessions close their ports on the way out.
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &set, nullptr);
    Daemon d(std::move(c));
    g_daemon = &d;
    std::thread signals([&] {
      int sig = 0;
      sigwait(&set, &sig);
      spdlog::info("signal {}: stopping", sig);
      d.stop();
    });
    d.run();
    // The signal thread waits in sigwait for SIGINT/SIGTERM, which every other
    // thread blocks: this SIGTERM is the one it takes, to end its wait.
    pthread_kill(signals.native_handle(), SIGTERM);  // NOLINT(bugprone-bad-signal-to-kill-thread): see above
    signals.join();
    g_daemon = nullptr;
  } catch (const std::exception& e) {
    spdlog::critical("cncstreamd: {}", e.what());
    return 2;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // What escapes run_daemon() (setting up the options or the log, or an
  // exception that is not an std::exception) ends the program with a
  // message, not std::terminate.
  try {
    return run_daemon(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "cncstreamd: " << e.what() << "\n";
  } catch (...) {
    std::cerr << "cncstreamd: an unknown exception\n";
  }
  return 2;
}
