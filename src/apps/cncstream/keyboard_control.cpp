#include "keyboard_control.hpp"

#include "job_display.hpp"
#include "terminal_keys.hpp"

#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>

namespace cncstream::app {

namespace {
termios g_saved{};
}

const char* KeyboardControl::help() { return job_keys_help(); }

KeyboardControl::KeyboardControl(session::StreamRunner& runner)
    : KeyboardControl(JobKeyActions{[&runner] { runner.request_toggle_pause(); }, [&runner] { runner.request_stop(); },
                                    [&runner](protocol::Realtime r) { runner.request_realtime(r); },
                                    [&runner](bool yes) { runner.request_tool_change_answer(yes); }}) {}

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

void KeyboardControl::note(std::string text) {
  std::lock_guard<std::mutex> l(note_mu_);
  note_ = std::move(text);
}

std::optional<std::string> KeyboardControl::take_note() {
  std::lock_guard<std::mutex> l(note_mu_);
  return std::exchange(note_, std::nullopt);
}

void KeyboardControl::loop() {
  using protocol::Realtime;
  const auto t0 = std::chrono::steady_clock::now();
  const auto now = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  KeyDecoder decoder;
  while (running_) {
    std::vector<KeyEvent> keys;
    pollfd p{STDIN_FILENO, POLLIN, 0};
    if (::poll(&p, 1, 100) > 0 && (p.revents & POLLIN)) {
      char buf[64];
      const ssize_t n = ::read(STDIN_FILENO, buf, sizeof buf);
      if (n > 0) keys = decoder.feed(std::string_view(buf, static_cast<std::size_t>(n)), now());
    } else if (auto k = decoder.expire(now())) {
      keys.push_back(*k);
    }
    for (const KeyEvent& k : keys) {
      if (jog_key_of(k) != JogKey::None) {
        note(std::string("jog: a job is running (") + to_string(k.key) +
             " refused); jog before or after it with `cncstream jog PORT`");
        continue;
      }
      if (k.key != Key::Char) continue;  // Esc, function keys: nothing during a job
      const char c = k.ch;
      switch (c) {
        case ' ': actions_.toggle_pause(); break;
        case 's': case 'S': actions_.stop(); break;
        case 'c': case 'C':
        case 'x': case 'X':
          if (actions_.tool_change_answer) actions_.tool_change_answer(c == 'c' || c == 'C');
          else note("no tool change here to confirm or decline");
          break;
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
}

}  // namespace cncstream::app
