#include "terminal_progress.hpp"

#include <unistd.h>

#include <map>
#include <string>

#include "terminal_text.hpp"

namespace cncstream::app {

void add_progress_option(CLI::App* sub, ProgressMode& mode) {
  const std::map<std::string, ProgressMode> names{
      {"auto", ProgressMode::Auto}, {"always", ProgressMode::Always}, {"never", ProgressMode::Never}};
  sub->add_option("--progress", mode, "Progress line on stderr: auto (when it is a terminal), always or never")
      ->transform(CLI::CheckedTransformer(names, CLI::ignore_case))
      ->default_str("auto");
}

TerminalProgress::TerminalProgress(std::FILE* out, ProgressMode mode)
    : out_(out),
      enabled_(mode == ProgressMode::Always || (mode == ProgressMode::Auto && ::isatty(::fileno(out)))) {}

void TerminalProgress::report(std::string_view stage, double fraction) {
  if (!enabled_) return;
  std::lock_guard<std::mutex> l(mutex_);
  const double now = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  if (!pacer_.should_draw(now, fraction)) return;
  // Back to the line's start, the text, then erase what a longer line left.
  std::string line = "\r";
  line.append(jobs::progress_line(stage, fraction, now)).append("\x1b[K");
  put_text(out_, line);
  shown_ = true;
}

void TerminalProgress::clear() {
  if (!enabled_) return;
  std::lock_guard<std::mutex> l(mutex_);
  if (!shown_) return;
  put_text(out_, "\r\x1b[K");
  shown_ = false;
  pacer_.reset();
}

}  // namespace cncstream::app
