// `cncstream jog PORT`: jog the machine from the keyboard with a DRO line.
// One thread: the machine session, the keys (stdin in raw mode, read with
// asio on the session's io_context, so a key reaches the port in the same
// call) and the display. A held key is a continuous jog only while the
// terminal's auto-repeat keeps coming (jog_control.hpp); quitting, a signal,
// a closed stdin or a lost link all release it.
#include <fmt/core.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/posix/stream_descriptor.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>

#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <csignal>
#include <cstdio>
#include <functional>
#include <iostream>
#include <memory>

#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/protocol/machine_actions.hpp"
#include "cncstream/session/machine_session.hpp"
#include "cncstream/transport/serial_transport.hpp"
#include "commands.hpp"
#include "job_session.hpp"
#include "jog_control.hpp"
#include "terminal_text.hpp"

namespace cncstream::app {

namespace {

// Raw keys for as long as it lives: no line editing, no echo, and Ctrl-C,
// Ctrl-Z, Ctrl-S arrive as bytes (Ctrl-C quits through the same path as
// `q`, releasing the jog; a suspended process would leave a jog to the
// controller). Output processing stays, so '\n' still returns the carriage.
class RawTerminal {
 public:
  explicit RawTerminal(int fd) : fd_(fd) {
    if (!::isatty(fd) || ::tcgetattr(fd, &saved_) != 0) return;
    termios raw = saved_;
    raw.c_lflag &= static_cast<tcflag_t>(~(ICANON | ECHO | ISIG | IEXTEN));
    raw.c_iflag &= static_cast<tcflag_t>(~(IXON | ICRNL));
    raw.c_cc[VMIN] = 1;
    raw.c_cc[VTIME] = 0;
    active_ = ::tcsetattr(fd, TCSANOW, &raw) == 0;
  }
  ~RawTerminal() {
    if (active_) ::tcsetattr(fd_, TCSANOW, &saved_);
  }
  RawTerminal(const RawTerminal&) = delete;
  RawTerminal& operator=(const RawTerminal&) = delete;

 private:
  int fd_;
  termios saved_{};
  bool active_ = false;
};

// The DRO line: redrawn in place on a terminal (cut to its width so it
// never wraps), a plain line per change otherwise. Other lines go above it.
class DroPrinter {
 public:
  DroPrinter(std::FILE* out, bool tty) : out_(out), tty_(tty) {}
  void draw(const std::string& line) {
    if (tty_) put_text(out_, "\r" + fit(line) + "\x1b[K");
    else if (line != last_) put_text(out_, line + "\n");
    last_ = line;
  }
  void print(const std::string& text) {
    if (tty_) put_text(out_, "\r\x1b[K" + text + "\n" + fit(last_) + "\x1b[K");
    else put_text(out_, text + "\n");
  }
  void finish() {
    put_text(out_, tty_ ? "\n" : "");
  }

 private:
  std::string fit(const std::string& s) const {
    winsize w{};
    const int width = ::ioctl(::fileno(out_), TIOCGWINSZ, &w) == 0 && w.ws_col > 10 ? w.ws_col - 1 : 0;
    if (width > 3 && static_cast<int>(s.size()) > width) return s.substr(0, static_cast<std::size_t>(width - 3)) + "...";
    return s;
  }
  std::FILE* out_;
  bool tty_;
  std::string last_;
};

struct JogCliOptions {
  ConnectionOptions conn;
  SimCliOptions sim;
  double step_mm = 0.1;
  double feed_mm_min = 0;
  std::string trace;
  protocol::MachineActionSettings actions;
  double quit_wait_s = 2.0;  // how long `q` waits for a moving jog to stop before closing the port
};

int run_jog(const JogCliOptions& o) {
  JogControlOptions jo;
  const auto step = std::find(jo.steps_mm.begin(), jo.steps_mm.end(), o.step_mm);
  if (step == jo.steps_mm.end()) throw std::invalid_argument("--step: one of 0.01, 0.1, 1, 10 (the keys 1-4)");
  jo.step_index = static_cast<std::size_t>(step - jo.steps_mm.begin());
  jo.feed_mm_min = o.feed_mm_min;

  session::MachineOptions mo;
  mo.name = o.conn.port;
  if (o.conn.port == "sim") {
    auto sim = std::make_shared<session::SimulatorPort>(simulator_options(o.sim));
    std::cerr << "simulator: GRBL 1.1h on " << sim->path() << " (speed " << o.sim.speed << ")\n";
    mo.port = sim;
  } else {
    const auto device = device_path(o.conn.port);
    if (!device) return 2;
    mo.port = std::make_shared<session::DevicePort>(*device);
    // A board that comes back (a USB cable re-plugged) is opened again; a
    // jog never resumes by itself: it needs fresh key presses.
    mo.reconnect_interval_s = 1.0;
  }
  mo.serial = transport::parse_serial_settings(o.conn.serial);
  mo.profiles_dir = protocol::default_profiles_dir();
  if (!o.conn.profile.empty()) mo.force_profile = o.conn.profile;
  mo.actions = o.actions;

  std::unique_ptr<std::FILE, int (*)(std::FILE*)> trace_file(nullptr, &std::fclose);
  if (!o.trace.empty()) {
    trace_file.reset(std::fopen(o.trace.c_str(), "w"));
    if (!trace_file) throw std::runtime_error("--trace: cannot write " + o.trace);
    // Each line flushed whole, so that a killed process leaves every line it traced.
    jo.trace = [f = trace_file.get()](const std::string& line) { put_text(f, line + "\n"); };
  }

  boost::asio::io_context io;
  session::MachineSession session(io, mo);
  boost::asio::posix::stream_descriptor keys(io);
  {
    const int fd = ::dup(STDIN_FILENO);
    boost::system::error_code ec;
    if (fd < 0 || keys.assign(fd, ec)) {
      if (fd >= 0) ::close(fd);
      throw std::runtime_error("jog reads its keys from stdin, which must be a terminal or a pipe" +
                               (ec ? " (" + ec.message() + ")" : std::string()));
    }
  }
  RawTerminal raw(STDIN_FILENO);
  DroPrinter dro(stdout, ::isatty(STDOUT_FILENO));
  JogControl control(session, jo);
  control.on_change = [&] { dro.draw(format_dro_line(control.view())); };
  control.on_print = [&](const std::string& line) { dro.print(line); };

  bool quitting = false, closed = false;
  boost::asio::steady_timer quit_deadline(io);
  boost::asio::signal_set signals(io, SIGINT, SIGTERM, SIGHUP);
  auto close_port = [&] {
    if (closed) return;
    closed = true;
    quit_deadline.cancel();
    session.close();  // the loop ends once the last byte is out
  };
  auto moving = [&] {
    const auto st = session.status();
    return session.snapshot().jogging || (st && st->state == protocol::MachineState::Jog);
  };
  auto quit = [&](const std::string& why) {
    if (quitting) return;
    quitting = true;
    control.stop_jog(why);
    boost::system::error_code ignored;
    keys.cancel(ignored);
    signals.cancel(ignored);
    // Leave the machine idle: steps still queued or moving are cancelled too.
    if (!moving()) return close_port();
    session.stop();
    quit_deadline.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(o.quit_wait_s)));
    quit_deadline.async_wait([&](const boost::system::error_code& ec) {
      if (!ec) close_port();
    });
  };
  control.on_quit = [&] { quit("quit"); };

  const bool verbose = o.conn.verbose;
  auto subscription = session.subscribe([&](const session::SessionEvent& e) {
    control.on_session_event(e);
    using session::SessionEventKind;
    if (e.kind == SessionEventKind::Log || e.kind == SessionEventKind::Link) dro.print(e.text);
    if (e.kind == SessionEventKind::Controller) {
      using protocol::EventKind;
      const auto& c = e.controller;
      if (c.kind == EventKind::Alarm) dro.print("ALARM: " + c.text);
      else if (c.kind == EventKind::Warning || (verbose && c.kind != EventKind::Status)) dro.print(c.text);
      if (quitting && !closed && c.kind == EventKind::Status && !moving()) close_port();
    }
  });

  signals.async_wait([&](const boost::system::error_code& ec, int sig) {
    if (!ec) quit(sig == SIGHUP ? "the terminal went away (SIGHUP)" : sig == SIGTERM ? "SIGTERM" : "SIGINT");
  });
  std::array<char, 512> buffer{};
  std::function<void()> read_keys = [&] {
    keys.async_read_some(boost::asio::buffer(buffer), [&](const boost::system::error_code& ec, std::size_t n) {
      if (ec) {
        if (ec != boost::asio::error::operation_aborted)
          quit(ec == boost::asio::error::eof ? "stdin closed" : "stdin: " + ec.message());
        return;
      }
      control.on_bytes(std::string_view(buffer.data(), n));
      if (!quitting) read_keys();
    });
  };

  dro.print(jog_keys_help());
  session.open();  // throws naming the port when it cannot be opened
  read_keys();
  io.run();
  dro.draw(format_dro_line(control.view()));
  dro.finish();
  if (jo.trace) {
    jo.trace(fmt::format("{:.4f} exit", session.now()));
  }
  return 0;
}

}  // namespace

void register_jog(CLI::App& app, CommandRegistry& registry) {
  auto o = std::make_shared<JogCliOptions>();
  auto* sub = app.add_subcommand(
      "jog",
      "Jog the machine from the keyboard: arrows X/Y, PgUp/PgDn Z (a tap is one step, a held key jogs until it is "
      "let go), 1-4 step size, 0 zero, h home, u unlock, q quit; a DRO line shows the position");
  sub->add_option("port", o->conn.port, "Serial port, 'auto' (the one known controller board) or 'sim'")->required();
  add_link_options(sub, o->conn);
  add_sim_machine_options(sub, o->sim);
  sub->add_option("--step", o->step_mm, "Step size to start with, mm: 0.01, 0.1, 1 or 10 (keys 1-4)")
      ->capture_default_str();
  sub->add_option("--feed", o->feed_mm_min,
                  "Jog feed, mm/min (default: 1000, or the controller's X/Y maximum rate when lower); +/- change it")
      ->check(CLI::PositiveNumber);
  sub->add_option("--trace", o->trace,
                  "Write a line per key, jog command and link change here, with the session's time in seconds");
  const char* g = "Machine actions";
  sub->add_option("--safe-z", o->actions.safe_z_mm, "Work Z that clears clamps and stock (keys s and g), mm")
      ->capture_default_str()->group(g);
  sub->add_option("--probe-plate", o->actions.probe_plate_mm,
                  "Touch plate thickness, mm (key p sets work Z to it at the touch; 0: probing the stock itself)")
      ->capture_default_str()->check(CLI::NonNegativeNumber)->group(g);
  sub->add_option("--probe-travel", o->actions.probe_travel_mm, "How far down key p searches for the plate, mm")
      ->capture_default_str()->check(CLI::PositiveNumber)->group(g);
  sub->add_option("--probe-feed", o->actions.probe_feed_mm_min, "Probing feed, mm/min")
      ->capture_default_str()->check(CLI::PositiveNumber)->group(g);
  registry.add(sub, [o] { return run_jog(*o); });
}

}  // namespace cncstream::app
