// `cncstream view --follow` (see view_follow.hpp).
#include "view_follow.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <thread>

#include <fmt/core.h>

#include "cncstream/cam/deviation.hpp"
#include "cncstream/geometry/stl.hpp"
#include "cncstream/jobs/output_file.hpp"
#include "cncstream/viewer/headless.hpp"
#include "cncstream/viewer/live_cut.hpp"
#include "cncstream/viewer/window.hpp"
#include "daemon_client.hpp"

namespace cncstream::app {

namespace {

using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

std::optional<Vec3> vec3_of(const json& j, const char* key) {
  if (!j.is_object() || !j.contains(key) || !j[key].is_array() || j[key].size() < 3) return std::nullopt;
  const json& a = j[key];
  if (!a[0].is_number() || !a[1].is_number() || !a[2].is_number()) return std::nullopt;
  return Vec3{a[0].get<double>(), a[1].get<double>(), a[2].get<double>()};
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
  const double executing = num_or(progress, "executing_line", num_or(progress, "last_answered_line", 0));
  if (!(executing > 1)) return 0;
  const auto line = static_cast<std::uint32_t>(executing) - 1;  // 0-based, in progress
  const auto it = std::lower_bound(path.segments.begin(), path.segments.end(), line,
                                   [](const viewer::SegmentInfo& s, std::uint32_t l) { return s.line < l; });
  return static_cast<double>(it - path.segments.begin());
}

std::string job_status_text(long id, const std::string& state, const json& progress, double total_lines,
                            const std::string& message) {
  std::string t = fmt::format("job {} {}", id, state);
  const double line = num_or(progress, "executing_line", num_or(progress, "last_answered_line", 0));
  if (line > 0 && total_lines > 0) t += fmt::format(", line {:.0f} of {:.0f}", line, total_lines);
  if (!message.empty()) t += ": " + message;  // a tool change's pause, why it failed or stopped
  return t;
}

// Everything the follower knows of the job and shows of it.
struct Followed {
  long id = 0;
  std::string state, file_name;
  json progress;
  double total_lines = 0;
  Vec3 offset{};  // work coordinates -> the scene's frame
  viewer::Scene scene;
  std::optional<viewer::LiveCut> cut;
  std::optional<DesignHeights> design;
  double tolerance = 0.05;

  // The stock as it stands: coloured by its deviation from the part, or plain without one.
  viewer::CutSurface cut_surface() const {
    const std::vector<float> h = cut->heights();
    if (design) return viewer::cut_surface(cut->grid(), h, *design, tolerance);
    return {viewer::stock_surface(cut->grid(), h), {}};
  }
  std::string summary(double done) const {
    std::string s = fmt::format("job {} {}: {:.0f} of {} segments run", id, state, done, scene.program->size());
    if (cut) s += fmt::format(", {:.1f} mm3 removed", cut->removed_volume());
    return s;
  }
};

Followed load_followed(const DaemonClient& api, const FollowOptions& o) {
  Followed f;
  f.tolerance = o.tolerance;
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
  f.progress = obj_or(job, "progress");
  f.total_lines = num_or(obj_or(job, "program"), "lines", 0);
  const std::string program = api.get_text(jpath + "/gcode");

  std::optional<Mesh> part;
  if (!o.part.empty()) {
    part = load_stl(o.part).mesh;
  } else if (str_or(job, "kind") == "stl") {
    const json params = obj_or(job, "params");
    StlLoadOptions so;
    so.units = parse_length_unit(str_or(params, "units", "mm"));
    so.scale = num_or(params, "scale", 1);
    part = parse_stl(api.get_text("/api/v1/files/" + str_or(job, "file") + "/content"), f.file_name, so).mesh;
  }
  viewer::ToolpathOptions to;
  to.arc_tolerance = o.arc_tolerance;
  if (part)
    if (const auto ws = program_work_origin(program, part->bounds())) to.offset = -ws->offset;
  f.offset = to.offset;
  f.scene.program = viewer::build_toolpath(program, to);

  std::vector<viewer::MountedCutter> cutters = viewer::program_cutters(program);
  if (cutters.empty() && o.cutter) cutters.push_back({0, *o.cutter});
  if (!cutters.empty()) {
    f.scene.cutter = cutters.front().cutter;
    std::optional<Box3> stock = viewer::program_stock(program);
    if (stock) stock = Box3{stock->lo + f.offset, stock->hi + f.offset};
    viewer::LiveCutOptions lo;
    lo.work_z0 = f.offset.z;
    f.cut.emplace(*f.scene.program, std::move(cutters), stock, lo);
    if (part) f.design = design_heights(*part, f.cut->grid());
  } else {
    std::cout << "note: the program names no cutter: give --cutter SPEC to see the material it removes" << std::endl;
  }
  // With the removed material shown, the part is inside the stock (the cut's
  // colours compare with it); without, the part itself.
  if (part && !f.cut) f.scene.part = viewer::part_surface(*part);
  return f;
}

bool same_cutter(const Cutter& a, const Cutter& b) {
  return a.type == b.type && a.radius == b.radius && a.corner_radius == b.corner_radius;
}

// Brings the cut up to `target`, and the scene's timeline and cutter with it.
void catch_up(Followed& f, double target) {
  if (f.cut) {
    f.cut->advance(target);
    f.scene.cutter = f.cut->cutter_in_spindle();
  }
  f.scene.progress = target;
}

int screenshot_of_job(const DaemonClient& api, Followed& f, const FollowOptions& o) {
  catch_up(f, segments_done(*f.scene.program, f.state, f.progress));
  if (f.cut) f.scene.cut = f.cut_surface();
  if (f.state == "running" || f.state == "held") {
    const json m = api.get("/api/v1/machines/" + url_encode(o.machine));
    if (const auto wpos = vec3_of(obj_or(m, "status"), "wpos")) f.scene.cutter_at = *wpos + f.offset;
  }
  std::string renderer;
  const RgbImage img = viewer::screenshot(f.scene, o.view, o.width, o.height, &renderer);
  jobs::write_file_atomically(o.screenshot, [&](const std::filesystem::path& file) { write_png(file, img); });
  std::cout << f.summary(f.scene.progress) << "\n";
  if (f.design) std::cout << f.scene.cut->stats.summary() << "\n";
  std::cout << "screenshot " << o.screenshot << ": " << o.width << " x " << o.height << ", "
            << renderer << std::endl;
  return 0;
}

// The WebSocket side of a window: runs until `stop` or the job's end (and
// then, with until_done, closes the window through `close`).
void feed_window(const DaemonClient& api, Followed& f, const FollowOptions& o, viewer::LiveCursor& live,
                 const std::atomic<bool>& stop, std::atomic<bool>& close, std::atomic<bool>& lost) {
  std::string message;
  try {
    DaemonSocket ws(api);
    ws.send(json{{"type", "subscribe"}, {"machines", json::array({o.machine})}, {"id", 1}});
    // The job's state now (the socket tells only what changes from here on).
    const json job = api.get("/api/v1/jobs/" + std::to_string(f.id));
    f.state = str_or(job, "state");
    f.progress = obj_or(job, "progress");
    message = str_or(job, "message");
    double target = segments_done(*f.scene.program, f.state, f.progress);
    std::string said_state, shown_status;
    double shown_progress = -1;
    Cutter shown_cutter = f.scene.cutter.value_or(Cutter{});
    auto last_surface = Clock::now() - std::chrono::seconds(1);
    bool surface_stale = false;
    while (!stop) {
      const bool behind = f.cut && static_cast<double>(f.cut->segments_cut()) < std::floor(target);
      if (const auto m = ws.read(behind ? 0.001 : 0.1)) {
        const std::string type = str_or(*m, "type");
        if (type == "status" && str_or(*m, "machine") == o.machine) {
          if (const auto wpos = vec3_of(*m, "wpos")) live.set_cutter_position(*wpos + f.offset);
        } else if (type == "job" && m->contains("job") && (*m)["job"] == f.id) {
          f.state = str_or(*m, "state");
          f.progress = obj_or(*m, "progress");
          message = str_or(*m, "message");
          target = std::max(target, segments_done(*f.scene.program, f.state, f.progress));
        }
      }
      if (f.cut && static_cast<double>(f.cut->segments_cut()) < std::floor(target)) {
        // In slices, so the socket is read between them while a late viewer catches up.
        f.cut->advance(target, 2000);
        surface_stale = true;
        if (!same_cutter(f.cut->cutter_in_spindle(), shown_cutter)) live.set_cutter(shown_cutter = f.cut->cutter_in_spindle());
      }
      const bool caught_up = !f.cut || static_cast<double>(f.cut->segments_cut()) >= std::floor(target);
      const bool ended = job_state_is_final(f.state) && caught_up;
      if (surface_stale && (ended || Clock::now() - last_surface > std::chrono::milliseconds(250))) {
        live.set_cut(std::make_shared<const viewer::TriangleMesh>(f.cut_surface().mesh));
        last_surface = Clock::now();
        surface_stale = false;
      }
      // Only what changed wakes the window.
      const double shown = f.cut ? static_cast<double>(f.cut->segments_cut()) : std::floor(target);
      if (shown != shown_progress) live.set_progress(shown_progress = shown);
      const std::string status = job_status_text(f.id, f.state, f.progress, f.total_lines, message);
      if (status != shown_status) live.set_status(shown_status = status);
      if (f.state + message != said_state) {  // on the terminal: each new state or message
        said_state = f.state + message;
        std::cout << status << std::endl;
      }
      if (ended) {
        std::cout << f.summary(shown) << std::endl;
        if (o.until_done) close = true;
        live.set_status(status);  // wakes the window (to close it)
        return;
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
  const viewer::Toolpath& path = *f.scene.program;
  std::cout << "following job " << f.id << " on " << o.machine << " at " << api.address().url() << " ("
            << (f.file_name.empty() ? "unnamed" : f.file_name) << "): " << path.lines << " lines, " << path.size()
            << " segments, " << f.state << std::endl;
  if (f.cut)
    std::cout << "stock " << f.cut->grid().nx << " x " << f.cut->grid().ny << " nodes at "
              << fmt::format("{:.3f}", f.cut->grid().dx) << " mm" << (f.design ? ", coloured by deviation from the part" : "")
              << std::endl;
  if (!o.screenshot.empty()) return screenshot_of_job(api, f, o);

  // The window starts with what has run already; the feeder brings the rest.
  catch_up(f, segments_done(path, f.state, f.progress));
  if (f.cut) f.scene.cut = f.cut_surface();
  viewer::LiveCursor live;
  std::atomic<bool> stop{false}, close{false}, lost{false};
  viewer::WindowOptions wo;
  wo.width = o.width;
  wo.height = o.height;
  wo.view = o.view;
  wo.title = "cncstream view: " + o.machine;
  wo.live = &live;
  wo.after_frame = [&](const std::string&) { return !close; };
  std::thread feeder([&] { feed_window(api, f, o, live, stop, close, lost); });
  struct JoinFeeder {
    std::atomic<bool>& stop;
    std::thread& t;
    ~JoinFeeder() {
      stop = true;
      t.join();
    }
  } join{stop, feeder};
  viewer::run_window(f.scene, wo);
  return lost ? 1 : 0;
}

}  // namespace cncstream::app
