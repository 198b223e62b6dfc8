// `cncstream pendant PORT [--replay FILE]`: the XHC WHB04B pendant drives the
// machine on PORT (a device, `auto`, or `sim`). From the USB receiver until
// Ctrl-C; with --replay, from a file of timestamped reports, then the final
// position is printed (tests check it; anyone can replay a recorded pendant).
#include <fmt/core.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>

#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <optional>

#include "cncstream/pendant/pendant_controller.hpp"
#include "cncstream/pendant/pendant_usb.hpp"
#include "cncstream/pendant/replay_source.hpp"
#include "cncstream/pendant/usb_pendant_reader.hpp"
#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/session/machine_session.hpp"
#include "cncstream/session/simulator_port.hpp"
#include "commands.hpp"
#include "job_session.hpp"

namespace cncstream::app {

namespace {

struct PendantOptions {
  std::string port = "auto";
  std::string replay;
  std::string record;
  std::string serial = "115200";
  std::string profile;
  SimCliOptions sim;
  bool verbose = false;
  bool machine_coordinates = false;
  double settle_s = 1.0;
  double lease_s = 0.2;
  double step_feed = 0;
  double timeout_s = 0;
  std::vector<std::string> macros;
};

std::string axes_text(const protocol::Axes& a) {
  return fmt::format("{:.3f},{:.3f},{:.3f}", a[0], a[1], a[2]);
}

// After the replay: the machine has settled when two status reports a
// quarter second apart show it Idle at the same place.
class Settler {
 public:
  Settler(boost::asio::io_context& io, session::MachineSession& s, double deadline_s, std::function<void(bool)> done)
      : timer_(io), session_(s), deadline_s_(deadline_s), done_(std::move(done)) {}
  void start(double after_s) { wait(after_s); }

 private:
  void wait(double s) {
    timer_.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(s)));
    timer_.async_wait([this](const boost::system::error_code& ec) {
      if (!ec) check();
    });
  }
  void check() {
    const auto snap = session_.snapshot();
    const auto& st = snap.status;
    const bool idle = st && st->state == protocol::MachineState::Idle && st->mpos && !snap.jogging;
    if (idle && last_ && axes_text(*st->mpos) == *last_) return done_(true);
    last_ = idle ? std::optional<std::string>(axes_text(*st->mpos)) : std::nullopt;
    if (snap.now > deadline_s_) return done_(false);
    wait(0.25);
  }
  boost::asio::steady_timer timer_;
  session::MachineSession& session_;
  double deadline_s_;
  std::function<void(bool)> done_;
  std::optional<std::string> last_;
};

int run_pendant(const PendantOptions& o) {
  pendant::PendantConfig cfg;
  cfg.lease_s = o.lease_s;
  cfg.step_feed_mm_min = o.step_feed;
  cfg.work_coordinates = !o.machine_coordinates;
  cfg.macros = pendant::default_macros();
  for (const auto& m : o.macros) {
    auto [n, action] = pendant::parse_macro_option(m);
    cfg.macros[n] = action;
  }
  std::optional<std::vector<pendant::ReplayEntry>> replay;
  if (!o.replay.empty()) replay = pendant::load_replay(o.replay);  // bad files fail before any port opens

  session::MachineOptions mo;
  std::shared_ptr<session::SimulatorPort> sim;
  if (o.port == "sim") {
    sim = std::make_shared<session::SimulatorPort>(simulator_options(o.sim));
    mo.port = sim;
    std::cerr << "simulator: GRBL 1.1h on " << sim->path() << " (speed " << o.sim.speed << ")\n";
  } else {
    const auto device = device_path(o.port);
    if (!device) return 2;
    mo.port = std::make_shared<session::DevicePort>(*device);
  }
  mo.name = o.port;
  mo.serial = transport::parse_serial_settings(o.serial);
  mo.profiles_dir = protocol::default_profiles_dir();
  if (!o.profile.empty()) mo.force_profile = o.profile;
  // Live, the pendant outlives a controller's power cycle; a replay ends instead.
  mo.reconnect_interval_s = replay ? 0 : 1.0;

  boost::asio::io_context io;
  session::MachineSession session(io, mo);
  const bool verbose = o.verbose;
  auto say = [](const std::string& text) { std::cerr << text << "\n"; };
  auto watch = session.subscribe([&](const session::SessionEvent& e) {
    using session::SessionEventKind;
    if (e.kind == SessionEventKind::Link || e.kind == SessionEventKind::Log) say(e.text);
    if (e.kind == SessionEventKind::Controller) {
      const auto k = e.controller.kind;
      // Alarms, the jog engine's notes (a dead-man cancel) and refused commands always.
      if (k == protocol::EventKind::Alarm || k == protocol::EventKind::Warning ||
          (k == protocol::EventKind::CommandAnswered && e.text.find("error") != std::string::npos) ||
          (verbose && k != protocol::EventKind::Status))
        say(e.text);
    }
  });
  pendant::PendantController controller(session, cfg);
  controller.set_log([&](pendant::LogLevel level, const std::string& text) {
    if (level != pendant::LogLevel::Debug || verbose) say(text);
  });

  // --record: every input in the replay format, timed from the first one.
  std::ofstream record;
  std::optional<std::chrono::steady_clock::time_point> record_t0;
  if (!o.record.empty()) {
    record.open(o.record);
    if (!record) throw std::runtime_error("cannot write the recording " + o.record);
    record << "# cncstream pendant recording: replay with `cncstream pendant PORT --replay " << o.record << "`\n";
    controller.set_input_tap([&](pendant::PendantController::Input kind, const pendant::InputReport& bytes) {
      const auto now = std::chrono::steady_clock::now();
      if (!record_t0) record_t0 = now;
      record << std::llround(std::chrono::duration<double, std::milli>(now - *record_t0).count()) << " ";
      switch (kind) {
        case pendant::PendantController::Input::Report: record << pendant::hex_bytes(bytes.data(), bytes.size()); break;
        case pendant::PendantController::Input::Unplug: record << "unplug"; break;
        case pendant::PendantController::Input::Plug: record << "plug"; break;
      }
      record << std::endl;  // flushed: a recording cut short by Ctrl-C keeps what it has
    });
  }

  int code = 0;
  std::unique_ptr<pendant::PendantUsb> usb;
  std::unique_ptr<pendant::UsbPendantReader> reader;
  std::unique_ptr<pendant::ReplayPlayer> player;
  std::unique_ptr<Settler> settler;
  auto finish = [&](int exit_code) {
    code = exit_code;
    session.jog_release();
    session.close();
    io.stop();
  };

  boost::asio::signal_set signals(io, SIGINT, SIGTERM);
  signals.async_wait([&](const boost::system::error_code& ec, int) {
    if (!ec) finish(replay ? 1 : 0);
  });
  std::optional<boost::asio::steady_timer> time_limit;
  if (o.timeout_s > 0) {
    time_limit.emplace(io, std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                               std::chrono::duration<double>(o.timeout_s)));
    time_limit->async_wait([&](const boost::system::error_code& ec) {
      if (ec) return;
      std::cerr << "cncstream: error: --timeout reached\n";
      finish(1);
    });
  }

  if (replay) {
    player = std::make_unique<pendant::ReplayPlayer>(io, std::move(*replay));
    const double deadline = player->length_ms() / 1000 + 60;  // a generous bound: the state, not the time, ends it
    settler = std::make_unique<Settler>(io, session, deadline, [&](bool settled) {
      const auto st = session.status();
      if (st && st->wpos) std::cout << "WPos: " << axes_text(*st->wpos) << "\n";
      if (st && st->mpos) std::cout << "MPos: " << axes_text(*st->mpos) << "\n";
      const auto& n = controller.counters();
      std::cout << "pendant: " << n.reports << " reports (" << n.bad_reports << " ignored), " << n.steps_sent
                << " steps sent, " << n.steps_refused << " dropped, " << n.continuous_starts
                << " continuous jogs started" << std::endl;
      if (!settled) std::cerr << "cncstream: error: the machine did not settle (Idle, not moving) after the replay\n";
      finish(settled ? 0 : 1);
    });
    bool started = false;
    auto start_replay = session.subscribe([&](const session::SessionEvent& e) {
      if (e.kind != session::SessionEventKind::Link) return;
      if (e.link == session::LinkState::Disconnected && !player->finished()) {
        std::cerr << "cncstream: error: the controller went away during the replay\n";
        boost::asio::post(io, [&] { finish(1); });
      }
      if (e.link != session::LinkState::Ready || started) return;
      started = true;
      boost::asio::post(io, [&] {
        controller.connected();
        player->start(
            [&](const pendant::ReplayEntry& entry) {
              switch (entry.kind) {
                case pendant::ReplayKind::Report: controller.report(entry.report); break;
                case pendant::ReplayKind::Unplug: controller.unplugged("replay line " + std::to_string(entry.line)); break;
                case pendant::ReplayKind::Plug: controller.connected(); break;
              }
            },
            [&] { settler->start(o.settle_s); });
      });
    });
    // A controller that never answers must not leave the replay waiting forever.
    boost::asio::steady_timer ready_limit(io, std::chrono::seconds(30));
    ready_limit.async_wait([&](const boost::system::error_code& ec) {
      if (ec || started) return;
      std::cerr << "cncstream: error: the controller on " << o.port << " was not ready within 30 s\n";
      finish(1);
    });
    session.open();
    io.run();
  } else {
    usb = pendant::make_libusb_pendant();
    reader = std::make_unique<pendant::UsbPendantReader>(*usb, controller);
    // The controller may be switched on after the pendant: try its port every
    // second until it opens (after that the session reconnects by itself).
    boost::asio::steady_timer open_retry(io);
    std::string last_open_error;
    std::function<void()> try_open = [&] {
      try {
        session.open();
      } catch (const std::exception& e) {
        if (e.what() != last_open_error) std::cerr << "cncstream: " << e.what() << " (trying again every second)\n";
        last_open_error = e.what();
        open_retry.expires_after(std::chrono::seconds(1));
        open_retry.async_wait([&](const boost::system::error_code& ec) {
          if (!ec) try_open();
        });
      }
    };
    try_open();
    std::cerr << "pendant: running until Ctrl-C\n";
    io.run();
    reader.reset();  // the io_context has stopped: no handler runs beside it
  }
  if (sim) sim->finish(false);
  return code;
}

}  // namespace

void register_pendant(CLI::App& app, CommandRegistry& registry) {
  auto o = std::make_shared<PendantOptions>();
  auto* sub = app.add_subcommand(
      "pendant", "Drive a machine with the XHC WHB04B-4/-6 USB pendant (or replay recorded pendant reports)");
  sub->add_option("port", o->port, "Serial port, 'auto' (the one known controller board) or 'sim'")
      ->capture_default_str();
  sub->add_option("--replay", o->replay,
                  "Read timestamped reports from FILE instead of USB ('MS B0 .. B7' per line, '#' comments), "
                  "then print the final position")
      ->check(CLI::ExistingFile);
  sub->add_option("--record", o->record, "Write every pendant input to FILE in the --replay format (to debug a pendant)");
  sub->add_option("--settle", o->settle_s, "With --replay: seconds after the last report before the machine must be still")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sub->add_option("--lease", o->lease_s, "A continuous jog stops this many seconds after the last wheel report")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--step-feed", o->step_feed, "Feed of step jogs, mm/min (default: the machine's jog maximum, $110-$112)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--macro", o->macros, "N=ACTION: macro N (1-16) runs a built-in (@zero-all, @zero-selected, "
                                        "@unlock, @feed-100, @spindle-100, @toggle-coordinates) or G-code lines "
                                        "separated by ';'");
  sub->add_flag("--machine-coordinates", o->machine_coordinates, "The LCD starts with machine, not work, coordinates");
  sub->add_option("--serial", o->serial, "Baud and frame, e.g. 115200 or 115200,8N1");
  sub->add_option("--profile", o->profile, "Force a firmware profile (grbl-1.1, grblhal, fluidnc, marlin)");
  sub->add_option("--timeout", o->timeout_s, "Give up after this many seconds (0: never)")->check(CLI::NonNegativeNumber);
  sub->add_flag("-v,--verbose", o->verbose, "Print every pendant event and controller message");
  add_sim_machine_options(sub, o->sim);  // jogs want --sim-speed 1 (real time)
  registry.add(sub, [o] { return run_pendant(*o); });
}

}  // namespace cncstream::app
