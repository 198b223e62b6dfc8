#include "routine_session.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>

#include <fmt/format.h>

#include <csignal>
#include <iostream>
#include <string>

#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/session/machine_session.hpp"
#include "cncstream/transport/serial_transport.hpp"

namespace cncstream::app {

namespace {

// The session's link options (--serial, --profile) on `port`.
session::MachineOptions machine_options(const ConnectionOptions& conn, std::shared_ptr<session::MachinePort> port) {
  session::MachineOptions mo;
  mo.name = conn.port;
  mo.port = std::move(port);
  mo.serial = transport::parse_serial_settings(conn.serial);
  mo.profiles_dir = protocol::default_profiles_dir();
  if (!conn.profile.empty()) mo.force_profile = conn.profile;
  return mo;
}

}  // namespace

std::optional<protocol::GrblSettings> read_controller_settings(const ConnectionOptions& conn) {
  const auto device = device_path(conn.port);
  if (!device) return std::nullopt;
  boost::asio::io_context io;
  session::MachineSession session(io, machine_options(conn, std::make_shared<session::DevicePort>(*device)));
  std::optional<protocol::GrblSettings> settings;
  std::string why = "the controller did not become ready";
  boost::asio::steady_timer deadline(io);
  auto end = [&] {
    deadline.cancel();
    session.close();
  };
  auto subscription = session.subscribe([&](const session::SessionEvent& e) {
    using session::SessionEventKind;
    if (e.kind == SessionEventKind::Log) std::cerr << e.text << "\n";
    if (e.kind != SessionEventKind::Link) return;
    if (e.link == session::LinkState::Ready && !settings) {
      settings = session.settings();  // empty when the controller did not give them (said in the log)
      boost::asio::post(io, end);
    } else if (e.link == session::LinkState::Disconnected && !settings) {
      why = e.text;
      boost::asio::post(io, end);
    }
  });
  const double limit_s = conn.timeout_s > 0 ? conn.timeout_s : 30;
  deadline.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(limit_s)));
  deadline.async_wait([&](const boost::system::error_code& ec) {
    if (ec || settings) return;
    why = fmt::format("not ready within {:g} s", limit_s);
    session.close();
  });
  try {
    session.open();
  } catch (const std::exception& e) {
    std::cerr << "cncstream: " << e.what() << "\n";
    return std::nullopt;
  }
  io.run();
  if (!settings) std::cerr << "cncstream: " << *device << ": " << why << "\n";
  return settings;
}

int run_machine_routine(const ConnectionOptions& conn, const session::SimulatorOptions& sim,
                        const std::shared_ptr<protocol::MachineRoutine>& routine) {
  std::shared_ptr<session::MachinePort> port;
  std::shared_ptr<session::SimulatorPort> sim_port;
  if (conn.port == "sim") {
    sim_port = std::make_shared<session::SimulatorPort>(sim);
    std::cerr << "simulator: GRBL 1.1h on " << sim_port->path() << " (speed " << sim.speed << ")\n";
    port = sim_port;
  } else {
    const auto device = device_path(conn.port);
    if (!device) return 2;
    port = std::make_shared<session::DevicePort>(*device);
  }
  session::MachineOptions mo = machine_options(conn, port);

  boost::asio::io_context io;
  session::MachineSession session(io, mo);
  bool started = false, ended = false, ok = false;
  std::string why;
  boost::asio::signal_set signals(io, SIGINT, SIGTERM, SIGHUP);
  boost::asio::steady_timer deadline(io);
  auto finish = [&](bool success, const std::string& text) {
    if (ended) return;
    ended = true;
    ok = success;
    why = text;
    boost::system::error_code ignored;
    signals.cancel(ignored);
    deadline.cancel();
    session.close();
  };
  signals.async_wait([&](const boost::system::error_code& ec, int) {
    if (ec || ended) return;
    session.stop();  // a running routine ends; the move in flight is held
    finish(false, "interrupted: the " + std::string(routine->name()) + " was stopped (feed hold); reset the "
                  "controller before going on");
  });
  if (conn.timeout_s > 0) {
    deadline.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(conn.timeout_s)));
    deadline.async_wait([&](const boost::system::error_code& ec) {
      if (ec || ended) return;
      session.stop();
      finish(false, "timed out (--timeout)");
    });
  }
  auto subscription = session.subscribe([&](const session::SessionEvent& e) {
    using session::SessionEventKind;
    if (e.kind == SessionEventKind::Log) std::cerr << e.text << "\n";
    if (e.kind == SessionEventKind::Link) {
      std::cerr << e.text << "\n";
      if (e.link == session::LinkState::Ready && !started) {
        started = true;
        boost::asio::post(io, [&] {
          if (auto r = session.run_routine(routine); !r) finish(false, r.reason);
        });
      } else if (e.link == session::LinkState::Disconnected && !ended) {
        finish(false, e.text);
      }
    }
    if (e.kind == SessionEventKind::Controller) {
      using protocol::EventKind;
      const auto& c = e.controller;
      if (c.kind == EventKind::Alarm || c.kind == EventKind::Warning) std::cerr << c.text << "\n";
      else if (conn.verbose && c.kind != EventKind::Status) std::cerr << c.text << "\n";
    }
    if (e.kind == SessionEventKind::Routine) {
      if (e.routine_prompt) {
        std::cout << e.routine_prompt->text << "\n";
        // The simulator has no hands: with --yes its operator mounts what is asked.
        if (sim_port && conn.yes && e.routine_prompt->tool > 0 &&
            (e.routine_prompt->kind == protocol::PromptKind::MountTool ||
             e.routine_prompt->kind == protocol::PromptKind::ZeroManually))
          sim_port->operator_mount(e.routine_prompt->tool);
        // Asked outside the session's call: the answer may come from a person.
        boost::asio::post(io, [&] {
          bool yes = conn.yes;
          if (yes) {
            std::cout << "(--yes: confirmed)\n";
          } else {
            std::cout << "confirm? [y/N] " << std::flush;
            std::string answer;
            yes = static_cast<bool>(std::getline(std::cin, answer)) && (answer == "y" || answer == "Y" || answer == "yes");
          }
          if (yes) session.routine_confirm();
          else session.routine_decline();
        });
      } else if (e.routine_succeeded) {
        boost::asio::post(io, [&, success = *e.routine_succeeded, text = e.text] { finish(success, text); });
      }
    }
  });
  session.open();
  io.run();
  if (ok) {
    std::cout << why << "\n";
    return 0;
  }
  std::cerr << "cncstream: " << why << "\n";
  return 1;
}

}  // namespace cncstream::app
