// The window on a private Xvfb server: it opens a 3.3 core context, draws,
// shows the timeline in its title, and follows a live job through the
// LiveCursor seam (set from another thread, as the daemon's client will).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "cncstream/viewer/window.hpp"

using namespace cncstream;
using namespace cncstream::viewer;

namespace {

// Xvfb on a display it picks itself (-displayfd): no fixed number to clash
// with other test runs, and its answer says it is ready.
class PrivateXServer {
 public:
  PrivateXServer() {
    int fds[2];
    if (::pipe(fds) != 0) return;
    pid_t pid = ::fork();
    if (pid == 0) {
      ::close(fds[0]);
      const std::string fd = std::to_string(fds[1]);
      ::execlp("Xvfb", "Xvfb", "-displayfd", fd.c_str(), "-screen", "0", "640x480x24", "-nolisten", "tcp",
               static_cast<char*>(nullptr));
      ::_exit(127);
    }
    ::close(fds[1]);
    pid_ = pid;
    std::string number;
    char c = 0;
    while (::read(fds[0], &c, 1) == 1 && c != '\n') number += c;
    ::close(fds[0]);
    if (!number.empty()) display_ = ":" + number;
  }
  ~PrivateXServer() {
    if (pid_ > 0) {
      ::kill(pid_, SIGTERM);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  PrivateXServer(const PrivateXServer&) = delete;
  PrivateXServer& operator=(const PrivateXServer&) = delete;
  const std::string& display() const { return display_; }

 private:
  pid_t pid_ = -1;
  std::string display_;
};

}  // namespace

TEST(ViewerWindow, DrawsAndFollowsALiveJob) {
  const PrivateXServer x;
  ASSERT_FALSE(x.display().empty()) << "Xvfb did not start (scripts/setup.sh installs xvfb)";
  const char* old_display = std::getenv("DISPLAY");
  const std::string saved = old_display ? old_display : "";
  ::setenv("DISPLAY", x.display().c_str(), 1);

  Scene scene;
  scene.program = Toolpath{};
  for (int k = 0; k < 100; ++k)
    append_segment(*scene.program, {k * 1.0, 0, 0}, {k + 1.0, 0, 0}, false, 500, static_cast<std::uint32_t>(k), 0);
  scene.cutter = Cutter::ball(3);
  LiveCursor live;
  WindowOptions o;
  o.width = 320;
  o.height = 200;
  o.live = &live;
  std::vector<std::string> titles;
  std::thread job;
  o.after_frame = [&](const std::string& title) {
    titles.push_back(title);
    if (titles.size() == 1) {
      // The job reports from its own thread; the window wakes for it.
      job = std::thread([&live] {
        live.set_cutter_position({5, 0, 0});
        live.set_progress(5);
      });
      return true;
    }
    return title.find("segment 5 of 100") == std::string::npos;
  };
  run_window(scene, o);
  if (job.joinable()) job.join();
  if (old_display) ::setenv("DISPLAY", saved.c_str(), 1);
  else ::unsetenv("DISPLAY");

  ASSERT_GE(titles.size(), 2u);
  EXPECT_NE(titles.front().find("segment 100 of 100, line 100"), std::string::npos) << titles.front();
  EXPECT_NE(titles.back().find("segment 5 of 100, line 6"), std::string::npos) << titles.back();
  ASSERT_TRUE(scene.cutter_at);
  EXPECT_EQ(scene.cutter_at->x, 5);
  EXPECT_EQ(scene.progress, 5);
}
