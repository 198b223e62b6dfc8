#pragma once
// A routine outside a job (protocol/machine_routine.hpp) against the
// in-process simulated GRBL 1.1, driven as the machine session drives it:
// one line at a time after the last one's ok, [..] lines and status reports
// in, an alarm aborts it. Virtual time: deterministic.
#include <functional>
#include <string>
#include <vector>

#include "cncsim/machine.hpp"
#include "cncstream/protocol/machine_routine.hpp"
#include "cncstream/protocol/status_report.hpp"

namespace cncstream::test {

inline std::vector<std::string> controller_lines(const std::string& out) {
  std::vector<std::string> v;
  std::string cur;
  for (char c : out) {
    if (c == '\n') {
      if (!cur.empty() && cur.back() == '\r') cur.pop_back();
      if (!cur.empty()) v.push_back(cur);
      cur.clear();
    } else {
      cur.push_back(c);
    }
  }
  return v;
}

struct RoutineBench {
  cncsim::Machine m;
  std::vector<std::string> sent, prompts;
  std::string alarms;
  bool answer_yes = true;

  explicit RoutineBench(cncsim::MachineOptions o) : m(std::move(o)) { m.take_output(); }
  void command(const std::string& l) {
    m.receive(l + "\n");
    m.run_until_idle();
    m.take_output();
  }
  // `each` runs every 50 ms of virtual time (to inject a hold, a loss...).
  void run(protocol::MachineRoutine& r, double max_s = 900, const std::function<void(double)>& each = {}) {
    r.start();
    for (double t = 0; t < max_s && !r.finished(); t += 0.05) {
      if (auto l = r.take_line()) {
        sent.push_back(*l);
        m.receive(*l + "\n");
      }
      if (auto p = r.take_prompt()) {
        prompts.push_back(p->text);
        if (answer_yes) r.confirm();
        else r.decline();
      }
      if (each) each(t);
      m.advance(0.05);
      for (const auto& l : controller_lines(m.take_output())) {
        if (l == "ok") r.on_answer(true, 0);
        else if (l.rfind("error:", 0) == 0) r.on_answer(false, std::stoi(l.substr(6)));
        else if (l.rfind("ALARM:", 0) == 0) {
          alarms += l;
          r.abort("alarm " + l);  // as the session does
        } else if (l.front() == '[') r.on_message(l);
      }
      if (auto st = protocol::parse_status_report(m.status_report())) r.on_status(*st);
    }
  }
  bool sent_any(const std::string& part) const {
    for (const auto& l : sent)
      if (l.find(part) != std::string::npos) return true;
    return false;
  }
};

}  // namespace cncstream::test
