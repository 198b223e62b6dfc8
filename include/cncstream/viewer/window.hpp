#pragma once
// The viewer's window (GLFW, OpenGL 3.3 core; needs an X display: a desktop
// or Xvfb). Left drag orbits, right or middle drag pans, the wheel zooms
// toward the cursor; keys 1-4 top/front/side/iso, F fits, C switches the
// program's colouring (feed / operation); left/right, Home/End and the
// slider at the bottom move the timeline; the title shows the position
// under the cursor (the depth buffer, unprojected) and the timeline's.
// Frames are drawn only when something changed: an idle viewer takes no CPU
// from a streamer beside it.
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>

#include "cncstream/viewer/camera.hpp"
#include "cncstream/viewer/scene.hpp"

namespace cncstream::viewer {

// No display to open a window on.
class NoDisplayError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The seam for following a live job: another thread (the daemon's
// WebSocket client) sets where the cutter is and which, how far the program
// has run, the material removed so far and a line of status; the window
// picks them up at its next frame.
class LiveCursor {
 public:
  void set_cutter_position(const geometry::Vec3& tip);
  void set_progress(double segments_done);
  void set_cut(std::shared_ptr<const TriangleMesh> surface);
  void set_cutter(const cam::Cutter& cutter);  // after a tool change
  void set_status(std::string text);  // shown in the title

  struct Update {
    std::optional<geometry::Vec3> cutter;
    std::optional<double> progress;
    std::shared_ptr<const TriangleMesh> cut;
    std::optional<cam::Cutter> tool;
    std::optional<std::string> status;
  };
  // What was set since the last take (nothing: both empty).
  Update take();
  // Called after every set (the window wakes its event loop with it).
  void on_change(std::function<void()> wake);

 private:
  // Applies `change` to what is pending, then wakes the window.
  void set(const std::function<void(Update&)>& change);
  std::mutex mutex_;
  Update pending_;
  std::function<void()> wake_;
};

struct WindowOptions {
  int width = 1280, height = 800;
  NamedView view = NamedView::Iso;
  std::string title = "cncstream view";
  PathColouring colouring = PathColouring::Feed;
  LiveCursor* live = nullptr;  // optional
  // Called after each frame with the window's title (the readouts); false
  // closes the window. For programs that embed the viewer, and its tests.
  std::function<bool(const std::string& title)> after_frame;
};

// Opens the window and runs until it is closed. Throws NoDisplayError (the
// message says how to get a screenshot instead) and gl::GlError.
void run_window(Scene& scene, const WindowOptions& options);

}  // namespace cncstream::viewer
