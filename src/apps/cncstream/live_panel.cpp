#include "live_panel.hpp"

#include <sys/ioctl.h>
#include <unistd.h>

#include <fmt/core.h>

#include <algorithm>

#include "terminal_text.hpp"

namespace cncstream::app {

namespace {
int terminal_width(std::FILE* f) {
  winsize w{};
  if (::ioctl(::fileno(f), TIOCGWINSZ, &w) == 0 && w.ws_col > 20) return w.ws_col - 1;
  return 100;
}
}  // namespace

LivePanel::LivePanel(std::FILE* out, bool tty, double plain_interval_s)
    : out_(out), tty_(tty), interval_(plain_interval_s) {}

void LivePanel::erase() {
  if (!tty_ || drawn_lines_ == 0) return;
  put_text(out_, fmt::format("\x1b[{}A\r\x1b[J", drawn_lines_));
  drawn_lines_ = 0;
}

void LivePanel::draw(const JobView& v) {
  if (tty_) {
    erase();
    const std::string text = format_job_panel(v, terminal_width(out_));
    put_text(out_, text);
    drawn_lines_ = static_cast<int>(std::count(text.begin(), text.end(), '\n'));
  } else {
    put_text(out_, format_job_line(v) + "\n");
  }
}

void LivePanel::update(const JobView& v, double now) {
  last_ = v;
  have_last_ = true;
  if (now - last_draw_ < (tty_ ? 0.2 : interval_)) return;
  last_draw_ = now;
  draw(v);
}

void LivePanel::message(const std::string& text) {
  erase();
  put_text(out_, text + "\n");
  if (tty_ && have_last_) draw(last_);
}

void LivePanel::finish(const JobView& v) {
  draw(v);
  drawn_lines_ = 0;
}

}  // namespace cncstream::app
