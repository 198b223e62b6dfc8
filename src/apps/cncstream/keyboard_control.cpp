#include "keyboard_control.hpp"

#include "job_display.hpp"

#include <poll.h>
#include <termios.h>
#include <unistd.h>

namespace cncstream::app {

namespace {
termios g_saved{};
}

const char* KeyboardControl::help() { return job_keys_help(); }

KeyboardControl::KeyboardControl(session::StreamRunner& runner)
    : KeyboardControl(JobKeyActions{[&runner] { runner.request_toggle_pause(); }, [&runner] { runner.request_stop(); },
                                    [&runner](protocol::Realtime r) { runner.request_realtime(r); }}) {}

KeyboardControl::KeyboardControl(JobKeyActions actions) : actions_(std::move(actions)) {
  if (!::isatty(STDIN_FILENO) || ::tcgetattr(STDIN_FILENO, &g_saved) != 0) return;
  termios raw = g_saved;
  raw.c_lflag &= static_cast<tcflag_t>(~(ICANON | ECHO));  // keep ISIG: Ctrl-C still stops
  raw.c_cc[VMIN] = 0;
  raw.c_cc[VTIME] = 0;
  if (::tcsetattr(STDIN_FILENO, TCSANOW, &raw) != 0) return;
  active_ = true;
  thread_ = std::thread([this] { loop(); });
}

KeyboardControl::~KeyboardControl() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
  if (active_) ::tcsetattr(STDIN_FILENO, TCSANOW, &g_saved);
}

void KeyboardControl::loop() {
  using protocol::Realtime;
  while (running_) {
    pollfd p{STDIN_FILENO, POLLIN, 0};
    if (::poll(&p, 1, 100) <= 0 || !(p.revents & POLLIN)) continue;
    char c = 0;
    if (::read(STDIN_FILENO, &c, 1) != 1) continue;
    switch (c) {
      case ' ': actions_.toggle_pause(); break;
      case 's': case 'S': actions_.stop(); break;
      case '+': actions_.realtime(Realtime::FeedOvPlus10); break;
      case '-': actions_.realtime(Realtime::FeedOvMinus10); break;
      case ']': actions_.realtime(Realtime::FeedOvPlus1); break;
      case '[': actions_.realtime(Realtime::FeedOvMinus1); break;
      case '0': actions_.realtime(Realtime::FeedOvReset); break;
      case '>': actions_.realtime(Realtime::SpindleOvPlus10); break;
      case '<': actions_.realtime(Realtime::SpindleOvMinus10); break;
      case '1': actions_.realtime(Realtime::RapidOvReset); break;
      case '2': actions_.realtime(Realtime::RapidOvMedium); break;
      case '3': actions_.realtime(Realtime::RapidOvLow); break;
      case '?': case 'h': show_help_ = !show_help_; break;
      default: break;
    }
  }
}

}  // namespace cncstream::app
