#pragma once
// The terminal edge of the job display: on a TTY the panel is redrawn in
// place (a few times a second); otherwise one plain progress line every few
// seconds. Messages (errors, alarms) are printed above the panel.
#include <cstdio>
#include <string>

#include "job_display.hpp"

namespace cncstream::app {

class LivePanel {
 public:
  // `tty`: redraw in place; otherwise a line every `plain_interval_s`.
  LivePanel(std::FILE* out, bool tty, double plain_interval_s);
  void update(const JobView& v, double now);
  void message(const std::string& text);
  // Draws the final state once more and leaves the cursor below it.
  void finish(const JobView& v);

 private:
  void erase();
  void draw(const JobView& v);
  std::FILE* out_;
  bool tty_;
  double interval_;
  double last_draw_ = -1e9;
  int drawn_lines_ = 0;
  JobView last_;
  bool have_last_ = false;
};

}  // namespace cncstream::app
