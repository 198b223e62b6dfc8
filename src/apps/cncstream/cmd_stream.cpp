// `cncstream stream FILE PORT`: stream a G-code file to a GRBL-family or
// Marlin controller. Ctrl-C asks for a controlled stop (hold, wait for the
// motion to stop, soft reset); a second Ctrl-C forces exit.
#include <csignal>
#include <iostream>
#include <memory>

#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/transport/journal.hpp"
#include "cncstream/transport/port_discovery.hpp"
#include "cncstream/transport/stream_runner.hpp"
#include "commands.hpp"
#include "keyboard_control.hpp"

namespace cncstream::app {

namespace {

transport::StreamRunner* g_runner = nullptr;
volatile std::sig_atomic_t g_interrupts = 0;

extern "C" void on_sigint(int) {
  g_interrupts = g_interrupts + 1;
  if (g_interrupts >= 2) std::signal(SIGINT, SIG_DFL);
  if (g_runner) g_runner->request_stop();  // sets an atomic flag only
}

}  // namespace

void register_stream(CLI::App& app, CommandRegistry& registry) {
  struct Opts {
    std::string file, port = "auto", serial = "115200", profile, journal;
    bool check = false, no_journal = false, verbose = false;
  };
  auto o = std::make_shared<Opts>();
  auto* sub = app.add_subcommand("stream", "Stream a G-code file to the controller (GRBL 1.1, grblHAL, FluidNC, Marlin)");
  sub->add_option("file", o->file, "G-code file")->required()->check(CLI::ExistingFile);
  sub->add_option("port", o->port, "Serial port, or 'auto' (the one known controller board)");
  sub->add_option("--serial", o->serial, "Baud and frame, e.g. 115200 or 115200,8N1");
  sub->add_option("--profile", o->profile, "Force a firmware profile (grbl-1.1, grblhal, fluidnc, marlin)");
  sub->add_flag("--check", o->check, "Check-mode pass ($C): report every G-code error without moving");
  sub->add_option("--journal", o->journal, "Journal database (default: $XDG_STATE_HOME/cncstream/journal.sqlite)");
  sub->add_flag("--no-journal", o->no_journal, "Do not journal this job");
  sub->add_flag("-v,--verbose", o->verbose, "Print controller messages and status");
  registry.add(sub, [o] {
    transport::RunnerOptions ro;
    if (o->port == "auto") {
      const auto choice = transport::choose_auto_port(transport::list_ports());
      if (!choice.port) {
        std::cerr << "cncstream: error: " << choice.message << "\n";
        return 2;
      }
      std::cerr << choice.message << "\n";
      ro.port = choice.port->path;
    } else {
      ro.port = o->port;
    }
    ro.serial = transport::parse_serial_settings(o->serial);
    ro.profiles_dir = protocol::default_profiles_dir();
    if (!o->profile.empty()) ro.force_profile = o->profile;
    ro.mode = o->check ? protocol::JobMode::Check : protocol::JobMode::Run;
    if (!o->no_journal)
      ro.journal_path = o->journal.empty() ? transport::Journal::default_path() : std::filesystem::path(o->journal);
    ro.on_log = [](const std::string& s) { std::cerr << s << "\n"; };
    const bool verbose = o->verbose;
    ro.on_event = [verbose](const protocol::Event& e) {
      using protocol::EventKind;
      switch (e.kind) {
        case EventKind::LineAnswered: return;
        case EventKind::Status:
          if (verbose) std::cerr << "status: " << e.text << "\n";
          return;
        case EventKind::Info:
        case EventKind::CommandAnswered:
          if (verbose) std::cerr << e.text << "\n";
          return;
        case EventKind::LineError:
          std::cerr << "ERROR at " << e.text << "\n  (the job is held: press Ctrl-C to stop)\n";
          return;
        case EventKind::Alarm: std::cerr << "ALARM: " << e.text << "\n"; return;
        default: std::cerr << to_string(e.kind) << ": " << e.text << "\n"; return;
      }
    };
    transport::StreamRunner runner(ro);
    g_runner = &runner;
    auto previous = std::signal(SIGINT, on_sigint);
    transport::RunResult r;
    try {
      KeyboardControl keys(runner);  // restores the terminal when the job ends
      if (keys.active()) std::cerr << KeyboardControl::help() << "\n";
      r = runner.run(o->file);
    } catch (...) {
      g_runner = nullptr;
      std::signal(SIGINT, previous);
      throw;
    }
    g_runner = nullptr;
    std::signal(SIGINT, previous);
    std::cerr << "outcome: " << to_string(r.outcome) << " (" << r.message << "); " << r.lines_answered
              << " lines answered, " << r.bytes_written << " bytes in " << r.seconds << " s";
    if (r.job_id) std::cerr << "; journal job " << r.job_id;
    std::cerr << "\n";
    return (r.outcome == protocol::JobOutcome::Completed || r.outcome == protocol::JobOutcome::CheckPassed) ? 0 : 1;
  });
}

}  // namespace cncstream::app
