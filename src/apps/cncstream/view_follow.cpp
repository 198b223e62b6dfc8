// `cncstream view --follow` (see view_follow.hpp).
#include "view_follow.hpp"

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <thread>

#include <fmt/core.h>

#include "cncstream/geometry/stl.hpp"
#include "cncstream/jobs/output_file.hpp"
#include "cncstream/viewer/headless.hpp"
#include "cncstream/viewer/window.hpp"
#include "daemon_client.hpp"
#include "live_view.hpp"

namespace cncstream::app {

namespace {

using json = nlohmann::json;

std::optional<geometry::Vec3> vec3_of(const json& j, const char* key) {
  if (!j.is_object() || !j.contains(key) || !j[key].is_array() || j[key].size() < 3) return std::nullopt;
  const json& a = j[key];
  if (!a[0].is_number() || !a[1].is_number() || !a[2].is_number()) return std::nullopt;
  return geometry::Vec3{a[0].get<double>(), a[1].get<double>(), a[2].get<double>()};
}

// The job to follow: the one named, else the machine's current job, else
// its first unfinished one in the queue.
long pick_job(const DaemonClient& api, const FollowOptions& o) {
  if (o.job) return *o.job;
  const json m = api.get("/api/v1/machines/" + url_encode(o.machine));
  if (m.contains("current_job") && m["current_job"].is_number_integer()) return m["current_job"].get<long>();
  const json list = api.get("/api/v1/jobs?machine=" + url_encode(o.machine));
  if (list.contains("jobs") && list["jobs"].is_array())
    for (const json& j : list["jobs"])
      if (!job_state_is_final(str_or(j, "state")) && j.contains("id") && j["id"].is_number_integer())
        return j["id"].get<long>();
  throw std::runtime_error(fmt::format("no job to follow on machine '{}' at {}: queue one, or name one with --job",
                                       o.machine, api.address().url()));
}

// The timeline position (segments) of a job's progress: every segment of
// the lines before the one executing; the whole program once it is done.
double segments_done(const viewer::Toolpath& path, const std::string& state, const json& progress) {
  if (state == "done") return static_cast<double>(path.size());
  return segments_before_line(
      path, static_cast<long>(num_or(progress, "executing_line", num_or(progress, "last_answered_line", 0))));
}

std::string job_status_text(long id, const std::string& state, const json& progress, double total_lines,
                            const std::string& message, const std::string& tool_change = {}) {
  std::string t = fmt::format("job {} {}", id, state);
  const double line = num_or(progress, "executing_line", num_or(progress, "last_answered_line", 0));
  if (line > 0 && total_lines > 0) t += fmt::format(", line {:.0f} of {:.0f}", line, total_lines);
  if (!message.empty()) t += ": " + message;  // a pause, why it failed or stopped
  if (!tool_change.empty()) t += ": " + tool_change;
  return t;
}

// The machine's tool change as the daemon's "tool_change" frame tells it
// (docs/api-v1.md): the line, the tools and the operator's prompt, or what
// the routine does; "" when none is going on.
std::string tool_change_text(const json& state) {
  if (!state.is_object()) return {};
  std::string t = fmt::format("tool change at line {} (T{} -> T{}, {})", num_or(state, "line", 0),
                              num_or(state, "from_tool", 0), num_or(state, "tool", 0), str_or(state, "method"));
  const json prompt = obj_or(state, "prompt");
  if (prompt.is_object() && !str_or(prompt, "text").empty()) return t + ": " + str_or(prompt, "text");
  return t + ": the machine moves";
}

// Everything the follower knows of the job and shows of it.
struct Followed {
  long id = 0;
  std::string state, file_name, message, tool_change;
  json progress;
  double total_lines = 0;
  std::unique_ptr<LiveScene> live;

  std::string status() const { return job_status_text(id, state, progress, total_lines, message, tool_change); }
  std::string summary(double done, double removed) const {
    std::string s = fmt::format("job {} {}: {:.0f} of {} segments run", id, state, done, live->scene.program->size());
    if (live->cut) s += fmt::format(", {:.1f} mm3 removed", removed);
    return s;
  }
};

Followed load_followed(const DaemonClient& api, const FollowOptions& o) {
  Followed f;
  f.id = pick_job(api, o);
  const std::string jpath = "/api/v1/jobs/" + std::to_string(f.id);
  json job = api.get(jpath);
  if (str_or(job, "machine") != o.machine)
    throw std::runtime_error(fmt::format("job {} runs on machine '{}', not '{}'", f.id, str_or(job, "machine"), o.machine));
  // Its program exists from `ready` on; a job being generated is waited for in a window.
  bool said = false;
  while (str_or(job, "state") == "queued" || str_or(job, "state") == "generating") {
    if (!o.screenshot.empty())
      throw std::runtime_error(fmt::format("job {} has no program yet ({})", f.id, str_or(job, "state")));
    if (!said) std::cout << "waiting for job " << f.id << "'s program (" << str_or(job, "state") << ")" << std::endl;
    said = true;
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    job = api.get(jpath);
  }
  f.state = str_or(job, "state");
  f.file_name = str_or(job, "file_name");
  f.message = str_or(job, "message");
  f.progress = obj_or(job, "progress");
  f.total_lines = num_or(obj_or(job, "program"), "lines", 0);
  const std::string program = api.get_text(jpath + "/gcode");

  std::optional<geometry::Mesh> part;
  if (!o.part.empty()) {
    part = geometry::load_stl(o.part).mesh;
  } else if (str_or(job, "kind") == "stl") {
    const json params = obj_or(job, "params");
    geometry::StlLoadOptions so;
    so.units = geometry::parse_length_unit(str_or(params, "units", "mm"));
    so.scale = num_or(params, "scale", 1);
    part = geometry::parse_stl(api.get_text("/api/v1/files/" + str_or(job, "file") + "/content"), f.file_name, so).mesh;
  }
  f.live = make_live_scene(program, std::move(part), false, o.cutter, std::nullopt, o.tolerance, o.arc_tolerance);
  if (!f.live->cut)
    std::cout << "note: the program names no cutter: give --cutter SPEC to see the material it removes" << std::endl;
  return f;
}

int screenshot_of_job(const DaemonClient& api, Followed& f, const FollowOptions& o) {
  LiveScene& s = *f.live;
  const double done = segments_done(*s.scene.program, f.state, f.progress);
  if (s.cut) {
    s.cut->advance(done);
    s.scene.cutter = s.cut->cutter_in_spindle();
    s.scene.cut = s.cut_surface();
  }
  s.scene.progress = done;
  if (f.state == "running" || f.state == "held") {
    const json m = api.get("/api/v1/machines/" + url_encode(o.machine));
    if (const auto wpos = vec3_of(obj_or(m, "status"), "wpos")) s.scene.cutter_at = *wpos + s.offset;
  }
  std::string renderer;
  const image::RgbImage img = viewer::screenshot(s.scene, o.view, o.width, o.height, &renderer);
  jobs::write_file_atomically(o.screenshot, [&](const std::filesystem::path& file) { image::write_png(file, img); });
  std::cout << f.summary(done, s.cut ? s.cut->removed_volume() : 0) << "\n";
  if (s.design) std::cout << s.scene.cut->stats.summary() << "\n";
  std::cout << "screenshot " << o.screenshot << ": " << o.width << " x " << o.height << ", " << renderer << std::endl;
  return 0;
}

// The WebSocket side of a window: reports into `feed` until `stop` or the
// job's end (then, with until_done, it closes the window through `close`).
void follow_socket(const DaemonClient& api, Followed& f, const FollowOptions& o, LiveFeed& feed,
                   viewer::LiveCursor& live, const std::atomic<bool>& stop, std::atomic<bool>& close,
                   std::atomic<bool>& lost) {
  try {
    DaemonSocket ws(api);
    ws.send(json{{"type", "subscribe"}, {"machines", json::array({o.machine})}, {"id", 1}});
    // The job's state now (the socket tells only what changes from here on).
    const json job = api.get("/api/v1/jobs/" + std::to_string(f.id));
    f.state = str_or(job, "state");
    f.progress = obj_or(job, "progress");
    f.message = str_or(job, "message");
    std::string said;
    while (!stop) {
      const viewer::Toolpath& path = *f.live->scene.program;
      if (f.state + f.message + f.tool_change != said) {  // on the terminal: each new state or message
        said = f.state + f.message + f.tool_change;
        std::cout << f.status() << std::endl;
      }
      if (job_state_is_final(f.state)) {
        feed.end(segments_done(path, f.state, f.progress), f.status());
        feed.wait_ended();
        std::cout << f.summary(feed.segments_cut(), feed.removed_volume()) << std::endl;
        if (o.until_done) close = true;
        live.set_status(f.status());  // wakes the window (to close it)
        return;
      }
      feed.progress(segments_done(path, f.state, f.progress), f.status());
      const auto m = ws.read(0.25);
      if (!m) continue;
      const std::string type = str_or(*m, "type");
      if (type == "status" && str_or(*m, "machine") == o.machine) {
        if (const auto wpos = vec3_of(*m, "wpos")) feed.position(*wpos);
        if (m->contains("tool_change")) f.tool_change = tool_change_text((*m)["tool_change"]);
      } else if (type == "job" && m->contains("job") && (*m)["job"] == f.id) {
        f.state = str_or(*m, "state");
        f.progress = obj_or(*m, "progress");
        f.message = str_or(*m, "message");
      } else if (type == "tool_change" && str_or(*m, "machine") == o.machine) {
        f.tool_change = tool_change_text(m->contains("state") ? (*m)["state"] : json());
      }
    }
  } catch (const std::exception& e) {
    lost = true;
    std::cerr << "cncstream view: the daemon's connection was lost: " << e.what() << std::endl;
    if (o.until_done) close = true;
    live.set_status(fmt::format("job {}: connection to the daemon lost", f.id));
  }
}

}  // namespace

int follow_job_in_viewer(const FollowOptions& o) {
  const DaemonClient api(parse_daemon_address(o.daemon.empty() ? default_daemon_address() : o.daemon),
                         "cncstream-view-" + std::to_string(::getpid()), daemon_token_from_env());
  Followed f = load_followed(api, o);
  LiveScene& s = *f.live;
  const viewer::Toolpath& path = *s.scene.program;
  std::cout << "following job " << f.id << " on " << o.machine << " at " << api.address().url() << " ("
            << (f.file_name.empty() ? "unnamed" : f.file_name) << "): " << path.lines << " lines, " << path.size()
            << " segments, " << f.state << "\n"
            << s.stock_text() << std::endl;
  if (!o.screenshot.empty()) return screenshot_of_job(api, f, o);

  // The window starts with the stock as it is; the feed cuts what has run.
  if (s.cut) s.scene.cut = s.cut_surface();
  viewer::LiveCursor live;
  std::atomic<bool> stop{false}, close{false}, lost{false};
  viewer::WindowOptions wo;
  wo.width = o.width;
  wo.height = o.height;
  wo.view = o.view;
  wo.title = "cncstream view: " + o.machine;
  wo.live = &live;
  wo.after_frame = [&](const std::string&) { return !close; };
  LiveFeed feed(s, live);
  std::thread socket([&] { follow_socket(api, f, o, feed, live, stop, close, lost); });
  struct JoinSocket {
    std::atomic<bool>& stop;
    std::thread& t;
    ~JoinSocket() {
      stop = true;
      t.join();
    }
  } join{stop, socket};
  viewer::run_window(s.scene, wo);
  return lost ? 1 : 0;
}

}  // namespace cncstream::app
