#pragma once
// The simulator on its pty, served by a thread that the test can pause (to
// read the machine or schedule faults without a race) and power-cycle (a
// fresh machine on a fresh pty, as after a lost link). A MachinePort, so a
// MachineSession opens it like a serial device; serving starts once the
// session has opened the port, so a fresh machine's banner reaches the host.
#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <thread>

#include "cncsim/machine.hpp"
#include "cncsim/pty_frontend.hpp"
#include "cncstream/session/machine_port.hpp"

namespace reliability {

class ServedSim final : public cncstream::session::MachinePort {
 public:
  // `on_machine` is called for each new machine (observers, faults) before it is served.
  ServedSim(cncsim::MachineOptions options, std::function<void(cncsim::Machine&)> on_machine)
      : options_(std::move(options)), on_machine_(std::move(on_machine)) {
    make_machine();
  }
  ~ServedSim() override { pause(); }
  ServedSim(const ServedSim&) = delete;
  ServedSim& operator=(const ServedSim&) = delete;

  std::string path() override { return path_; }
  void opened() override { serve(); }

  void serve() {
    if (thread_.joinable() || !front_) return;
    stop_ = false;
    thread_ = std::thread([this] {
      if (front_->run(stop_) == cncsim::PtyFrontEnd::Exit::Vanished) {
        front_.reset();  // the pty is gone
        vanished_ = true;
      }
    });
  }
  // Stops serving: the machine may be read and changed until serve().
  void pause() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  // The port went away and came back with a freshly powered machine.
  void power_cycle() {
    pause();
    front_.reset();
    make_machine();
  }
  bool vanished() const { return vanished_; }
  cncsim::Machine& machine() { return *machine_; }  // only while paused
  int power_cycles() const { return machines_ - 1; }

 private:
  void make_machine() {
    machine_ = std::make_unique<cncsim::Machine>(options_);
    if (on_machine_) on_machine_(*machine_);
    cncsim::PtyOptions po;
    po.speed = 0;  // --speed max
    front_ = std::make_unique<cncsim::PtyFrontEnd>(*machine_, po);
    path_ = front_->slave_path();
    vanished_ = false;
    ++machines_;
  }

  cncsim::MachineOptions options_;
  std::function<void(cncsim::Machine&)> on_machine_;
  std::unique_ptr<cncsim::Machine> machine_;
  std::unique_ptr<cncsim::PtyFrontEnd> front_;
  std::string path_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> vanished_{false};
  int machines_ = 0;
};

}  // namespace reliability
