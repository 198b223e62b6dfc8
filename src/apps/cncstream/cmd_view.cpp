// `cncstream view [PART.stl] [--program FILE.nc] [--cut RESULT.f32 --design
//  PART.stl] [--cutter SPEC --at X,Y,Z] [--screenshot OUT.png --view iso
//  --size 1280x800] [--follow MACHINE --daemon URL]`: the 3-D viewer
// (src/viewer/), in a window or one frame without one; --follow attaches it
// to a job on the daemon (view_follow.hpp).
#include <fmt/core.h>

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "cncstream/cam/height_field_io.hpp"
#include "cncstream/geometry/stl.hpp"
#include "cncstream/gl/gl_error.hpp"
#include "cncstream/jobs/output_file.hpp"
#include "cncstream/jobs/work_setup.hpp"
#include "cncstream/viewer/headless.hpp"
#include "cncstream/viewer/window.hpp"
#include "commands.hpp"
#include "live_view.hpp"
#include "view_follow.hpp"

namespace cncstream::app {

namespace {

// "X,Y,Z" -> a point; the option's name in the error.
geometry::Vec3 parse_view_point(const std::string& text, const char* option) {
  double v[3] = {0, 0, 0};
  std::size_t pos = 0;
  for (int k = 0; k < 3; ++k) {
    const std::size_t end = k < 2 ? text.find(',', pos) : text.size();
    const std::string part = end == std::string::npos ? std::string() : text.substr(pos, end - pos);
    const auto r = std::from_chars(part.data(), part.data() + part.size(), v[k]);
    if (part.empty() || r.ec != std::errc() || r.ptr != part.data() + part.size() || !std::isfinite(v[k]))
      throw std::invalid_argument(fmt::format("{} '{}': expected X,Y,Z in mm, e.g. 10,20,-1.5", option, text));
    pos = end + 1;
  }
  return {v[0], v[1], v[2]};
}

// "1280x800" -> width, height.
std::pair<int, int> parse_view_size(const std::string& text) {
  int w = 0, h = 0;
  const auto x = text.find('x');
  const bool ok = x != std::string::npos &&
                  std::from_chars(text.data(), text.data() + x, w).ptr == text.data() + x &&
                  std::from_chars(text.data() + x + 1, text.data() + text.size(), h).ptr == text.data() + text.size();
  if (!ok || w < 1 || h < 1 || w > 8192 || h > 8192)
    throw std::invalid_argument(fmt::format("--size '{}': expected WIDTHxHEIGHT in pixels, each 1..8192", text));
  return {w, h};
}


}  // namespace

std::optional<jobs::WorkSetup> program_work_origin(const std::string& text, const geometry::Box3& part) {
  const auto at = text.find("(work origin: XY at ");
  if (at > 4096) return std::nullopt;  // in the header, or not at all (npos)
  const std::string line = text.substr(at, text.find('\n', at) - at);
  XYOrigin xy = XYOrigin::PartMin;
  if (line.find("XY at part centre") != std::string::npos) xy = XYOrigin::PartCenter;
  else if (line.find("XY at model origin") != std::string::npos) xy = XYOrigin::Model;
  else if (line.find("XY at part minimum") == std::string::npos) return std::nullopt;
  ZZero z = ZZero::PartTop;
  if (line.find("Z0 at part bottom") != std::string::npos) z = ZZero::PartBottom;
  else if (line.find("Z0 at model origin") != std::string::npos) z = ZZero::Model;
  else if (line.find("Z0 at part top") == std::string::npos) return std::nullopt;
  return jobs::work_setup(part, xy, z);
}

void register_view(CLI::App& app, CommandRegistry& registry) {
  struct Opts {
    std::string part, program, cut, design, cutter, at, screenshot, view = "iso", size = "1280x800";
    std::string colour = "feed", program_offset = "auto";
    double tolerance = 0.05, arc_tolerance = 0.002;
    std::optional<double> timeline;
    std::string follow, daemon;
    std::optional<long> job;
    bool until_done = false;
  };
  auto o = std::make_shared<Opts>();
  auto* sub = app.add_subcommand("view", "Show a part, a program, a simulated cut and the cutter in 3-D (or one frame: --screenshot)");
  sub->add_option("part", o->part, "The part (STL), shaded");
  sub->add_option("--program", o->program, "A G-code program: cuts coloured by feed or operation, rapids dashed");
  sub->add_option("--colour", o->colour, "The program's cuts coloured by feed or by operation")
      ->check(CLI::IsMember({"feed", "operation"}));
  sub->add_option("--program-offset", o->program_offset,
                  "Where the program's work coordinates sit on the part: auto (from the work origin a cncstream program "
                  "names in its header), none, or DX,DY,DZ added to the program's points");
  sub->add_option("--arc-tolerance", o->arc_tolerance, "Chord error of the drawn arcs, mm")->check(CLI::PositiveNumber);
  sub->add_option("--cut", o->cut, "A simulated cut (cncsim --result .f32), coloured by its deviation from --design");
  sub->add_option("--design", o->design, "The design the cut is compared with (default: the part)");
  sub->add_option("--tolerance", o->tolerance, "Deviation within which the cut is on the design, mm")
      ->check(CLI::PositiveNumber);
  sub->add_option("--cutter", o->cutter, "Show the cutter: flat:D, ball:D, bull:D:r");
  sub->add_option("--at", o->at, "The cutter's tip at X,Y,Z (default: the timeline's point on the program)");
  sub->add_option("--timeline", o->timeline, "How much of the program has run, 0..1 (default all)")
      ->check(CLI::Range(0.0, 1.0));
  sub->add_option("--screenshot", o->screenshot, "Render one frame to this PNG without a window (EGL, no X)");
  sub->add_option("--view", o->view, "top, front, side or iso")->check(CLI::IsMember({"top", "front", "side", "iso"}));
  sub->add_option("--size", o->size, "WIDTHxHEIGHT of the window or screenshot, pixels");
  sub->add_option("--follow", o->follow,
                  "Follow a job on this machine of the daemon: its program, the cutter where the machine is, the "
                  "material removed as it runs (with --screenshot: one frame of it now)");
  sub->add_option("--daemon", o->daemon, "The daemon's URL for --follow (default $CNCSTREAM_DAEMON or "
                                         "http://127.0.0.1:8420)");
  sub->add_option("--job", o->job, "The job to follow (default: the machine's current job, else its next one)")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--until-done", o->until_done, "With --follow: close the window when the job has ended");
  registry.add(sub, [o] {
    using namespace viewer;
    const NamedView view = parse_named_view(o->view);
    const auto [width, height] = parse_view_size(o->size);
    if (!o->follow.empty()) {
      if (!o->program.empty() || !o->cut.empty() || !o->design.empty() || o->timeline || !o->at.empty())
        throw std::invalid_argument("--follow takes the program and the cut from the daemon's job: leave out "
                                    "--program, --cut, --design, --timeline and --at");
      FollowOptions fo;
      fo.daemon = o->daemon;
      fo.machine = o->follow;
      fo.job = o->job;
      fo.part = o->part;
      if (!o->cutter.empty()) fo.cutter = cam::parse_cutter_spec(o->cutter);
      fo.tolerance = o->tolerance;
      fo.arc_tolerance = o->arc_tolerance;
      fo.until_done = o->until_done;
      fo.screenshot = o->screenshot;
      fo.view = view;
      fo.width = width;
      fo.height = height;
      return follow_job_in_viewer(fo);
    }
    if (!o->daemon.empty() || o->job || o->until_done)
      throw std::invalid_argument("--daemon, --job and --until-done go with --follow MACHINE");
    Scene scene;
    std::optional<geometry::Mesh> part;
    if (!o->part.empty()) {
      part = geometry::load_stl(o->part).mesh;
      scene.part = part_surface(*part);
    }
    if (!o->cut.empty()) {
      if (o->design.empty() && !part) throw std::invalid_argument("--cut needs the design: give --design PART.stl or the part");
      const geometry::Mesh design = o->design.empty() ? *part : geometry::load_stl(o->design).mesh;
      cam::HeightFieldData field = cam::read_height_field(o->cut);
      if (field.work_offset) {
        // Cut in work coordinates (the job's simulator): into the design's
        // (and the part's, the program's) model coordinates.
        const geometry::Vec3 w = *field.work_offset;
        field.grid.x0 -= w.x;
        field.grid.y0 -= w.y;
        for (float& z : field.z) z = static_cast<float>(static_cast<double>(z) - w.z);
        std::cout << "cut placed on the design by its work origin: offset " << format_position(geometry::Vec3{} - w) << "\n";
      }
      scene.cut = cut_surface(field.grid, field.z, design, o->tolerance);
      std::cout << "cut " << o->cut << ": " << field.grid.nx << " x " << field.grid.ny << " nodes, "
                << scene.cut->stats.gouged << " gouged, " << scene.cut->stats.excess << " with excess (tolerance "
                << o->tolerance << " mm)\n";
    } else if (!o->design.empty()) {
      throw std::invalid_argument("--design goes with --cut");
    }
    if (!o->program.empty()) {
      const std::string text = read_program_text(o->program);
      viewer::ToolpathOptions to;
      to.arc_tolerance = o->arc_tolerance;
      if (o->program_offset == "auto") {
        const geometry::Box3 ref = part ? part->bounds() : geometry::Box3{};
        if (const auto ws = ref.empty() ? std::nullopt : program_work_origin(text, ref)) {
          to.offset = -ws->offset;
          std::cout << "program placed on the part by its work origin: offset "
                    << format_position(to.offset) << "\n";
        }
      } else if (o->program_offset != "none") {
        to.offset = parse_view_point(o->program_offset, "--program-offset");
      }
      scene.program = build_toolpath(text, to);
      if (o->colour != "feed") colour_toolpath(*scene.program, parse_path_colouring(o->colour));
      const Toolpath& p = *scene.program;
      std::cout << "program " << o->program << ": " << p.lines << " lines, " << p.size() << " segments ("
                << p.rapids << " rapid), " << p.arcs << (p.arcs == 1 ? " arc, " : " arcs, ") << p.operations.size()
                << (p.operations.size() == 1 ? " operation" : " operations") << "\n";
      if (!p.errors.empty()) {
        std::cerr << "cncstream view: " << p.errors.size() << " line" << (p.errors.size() == 1 ? "" : "s")
                  << " the controller would reject (skipped), first at line " << p.errors.front().line + 1
                  << ": error:" << p.errors.front().status << "\n";
      }
      if (o->timeline) scene.progress = *o->timeline * static_cast<double>(p.size());
    } else if (o->timeline) {
      throw std::invalid_argument("--timeline goes with --program");
    }
    if (!o->cutter.empty()) scene.cutter = cam::parse_cutter_spec(o->cutter);
    if (!o->at.empty()) {
      if (!scene.cutter) throw std::invalid_argument("--at places the cutter: give --cutter SPEC too");
      scene.cutter_at = parse_view_point(o->at, "--at");
    }
    if (scene.empty()) throw std::invalid_argument("nothing to show: give a part, --program, --cut or --cutter");

    if (!o->screenshot.empty()) {
      std::string renderer;
      const image::RgbImage img = screenshot(scene, view, width, height, &renderer);
      jobs::write_file_atomically(o->screenshot, [&](const std::filesystem::path& file) { image::write_png(file, img); });
      std::cout << "screenshot " << o->screenshot << ": " << width << " x " << height << ", " << o->view
                << " view, " << renderer << "\n";
      return 0;
    }
    WindowOptions wo;
    wo.width = width;
    wo.height = height;
    wo.view = view;
    wo.colouring = parse_path_colouring(o->colour);
    wo.title = "cncstream view";
    run_window(scene, wo);
    return 0;
  });
}

}  // namespace cncstream::app
