// The window on a private Xvfb server: it opens a 3.3 core context, draws,
// shows the timeline in its title, and follows a live job through the
// LiveCursor seam (set from another thread, as the daemon's client does):
// the cutter's position and tool, the timeline, the cut, a status line.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "cncstream/viewer/window.hpp"
#include "support/private_x_server.hpp"

using namespace cncstream;
using namespace cncstream::viewer;

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
  scene.cutter = cam::Cutter::ball(3);
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
        // The material removed so far and the tool changed to.
        cam::GridSpec g{0, -5, 1, 1, 11, 11};
        live.set_cut(std::make_shared<const TriangleMesh>(stock_surface(g, std::vector<float>(g.size(), -1.0f))));
        live.set_cutter(cam::Cutter::flat(6));
        live.set_status("job 7 running, line 6 of 100");
        live.set_progress(5);
      });
      return true;
    }
    return title.find("segment 5 of 100") == std::string::npos || title.find("job 7 running") == std::string::npos ||
           !scene.cut || !scene.cutter || scene.cutter->type != cam::CutterType::Flat;
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
  ASSERT_TRUE(scene.cut);
  EXPECT_EQ(scene.cut->mesh.triangles(), 200u);
  EXPECT_EQ(scene.cutter->radius, 3);
}
