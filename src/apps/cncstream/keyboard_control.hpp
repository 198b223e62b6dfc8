#pragma once
// Single-key operator control while a job streams (only when stdin is a
// terminal): space pause/resume, s stop, + / - feed ±10 %, ] / [ feed ±1 %,
// 0 feed 100 %, > / < spindle ±10 %, 1 2 3 rapid 100/50/25 %, ? toggles the
// key help in the live display. Keys are decoded whole (terminal_keys.hpp),
// so an arrow's escape sequence is not taken for its '[' (feed -1 %): the
// jog keys are refused with a note while the job runs.
#include <atomic>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "cncstream/session/stream_runner.hpp"

namespace cncstream::app {

// What the keys do: a local StreamRunner's requests, or the daemon's API
// calls when the job was handed to the daemon. Called on the key thread.
struct JobKeyActions {
  std::function<void()> toggle_pause;
  std::function<void()> stop;
  std::function<void(protocol::Realtime)> realtime;
  // At a tool change's prompt: c confirms (true), x declines (false).
  std::function<void(bool)> tool_change_answer;
};

class KeyboardControl {
 public:
  explicit KeyboardControl(session::StreamRunner& runner);
  explicit KeyboardControl(JobKeyActions actions);
  ~KeyboardControl();  // restores the terminal
  KeyboardControl(const KeyboardControl&) = delete;
  KeyboardControl& operator=(const KeyboardControl&) = delete;
  bool active() const { return active_; }
  static const char* help();
  bool help_shown() const { return show_help_; }
  // A note for the display (a refused key), once; from any thread.
  std::optional<std::string> take_note();

 private:
  void loop();
  void note(std::string text);
  std::mutex note_mu_;
  std::optional<std::string> note_;
  JobKeyActions actions_;
  std::atomic<bool> running_{true};
  bool active_ = false;
  std::atomic<bool> show_help_{false};
  std::thread thread_;
};

}  // namespace cncstream::app
