// G-code -> the viewer's line buffer (see toolpath_buffers.hpp).
#include "cncstream/viewer/toolpath_buffers.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <variant>

#include "cncstream/gcode/arc_segments.hpp"
#include "cncstream/gcode/grbl_codes.hpp"
#include "cncstream/gcode/line_lexer.hpp"
#include "cncstream/gcode/program.hpp"
#include "cncstream/image/category_map.hpp"

namespace cncstream::viewer {

Vec3 Toolpath::point_at(double t) const {
  if (segments.empty()) return {};
  const double n = static_cast<double>(segments.size());
  t = std::clamp(t, 0.0, n);
  if (t >= n) return to(segments.size() - 1);
  const auto k = static_cast<std::size_t>(t);
  const double f = t - static_cast<double>(k);
  return from(k) + (to(k) - from(k)) * f;
}

void append_segment(Toolpath& path, const Vec3& from, const Vec3& to, bool rapid, double feed, std::uint32_t line,
                    std::uint32_t operation) {
  PathVertex a{static_cast<float>(from.x), static_cast<float>(from.y), static_cast<float>(from.z), 0, 0, 0, 0, 0};
  PathVertex b{static_cast<float>(to.x), static_cast<float>(to.y), static_cast<float>(to.z), 0, 0, 0, 0, 0};
  if (rapid) {
    // The dash pattern runs on along consecutive rapids.
    const bool continues = !path.segments.empty() && path.vertices.back().flags == kRapid;
    a.along = continues ? path.vertices.back().along : 0.0f;
    b.along = a.along + static_cast<float>(norm(to - from));
    a.flags = b.flags = kRapid;
    ++path.rapids;
  } else {
    if (path.segments.size() == path.rapids) path.min_feed = path.max_feed = feed;  // the first cut
    path.min_feed = std::min(path.min_feed, feed);
    path.max_feed = std::max(path.max_feed, feed);
  }
  path.vertices.push_back(a);
  path.vertices.push_back(b);
  path.segments.push_back({static_cast<float>(rapid ? 0.0 : feed), line, operation});
  path.bounds.add(from);
  path.bounds.add(to);
}

Toolpath build_toolpath(std::string_view program, const ToolpathOptions& options) {
  Toolpath path;
  gcode::ParserState state = options.initial;
  const auto lines = gcode::split_lines(program);
  path.lines = lines.size();
  // What begins an operation is seen before its first move: the name (the
  // first comment-only line since the last move) and whether one begins.
  std::string pending_name;
  bool pending_new = false, moved = false;
  auto operation = std::uint32_t{0};
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const gcode::CleanLine c = gcode::clean_line(lines[i]);
    if (!c.overflow && c.text.empty()) {
      const std::string_view raw = lines[i];
      const auto open = raw.find_first_of("(;");
      if (open != std::string_view::npos && pending_name.empty()) {
        std::string_view name = raw.substr(open + 1);
        if (const auto close = name.find(')'); raw[open] == '(' && close != std::string_view::npos)
          name = name.substr(0, close);
        while (!name.empty() && (name.back() == '\r' || name.back() == ' ')) name.remove_suffix(1);
        while (!name.empty() && name.front() == ' ') name.remove_prefix(1);
        pending_name = std::string(name);
        pending_new = pending_new || moved;
      }
      continue;
    }
    if (!c.overflow && (c.text == "%" || c.text.front() == '$')) continue;
    gcode::BlockResult r;
    if (c.overflow) r.status = grbl::kOverflow;
    else r = gcode::execute_block(state, c.text);
    if (!r.ok()) {
      path.errors.push_back({i, r.status});
      continue;
    }
    if (r.state.tool != state.tool) pending_new = true;
    const Vec3 shift = options.offset - r.state.wco();
    const auto line = static_cast<std::uint32_t>(i);
    for (const gcode::Action& a : r.actions) {
      const bool moves = std::holds_alternative<gcode::LinearMove>(a) || std::holds_alternative<gcode::ArcMove>(a) ||
                         std::holds_alternative<gcode::ProbeMove>(a);
      if (!moves) continue;
      if (path.operations.empty() || (pending_new && moved)) {
        std::string name = pending_name;
        if (name.empty()) name = std::string("operation ").append(std::to_string(path.operations.size() + 1));
        path.operations.push_back(std::move(name));
        operation = static_cast<std::uint32_t>(path.operations.size() - 1);
        moved = false;
      } else if (pending_new && !pending_name.empty()) {
        path.operations.back() = pending_name;  // nothing drawn in it yet: renamed
      }
      pending_new = false;
      pending_name.clear();
      if (const auto* m = std::get_if<gcode::LinearMove>(&a)) {
        if (m->from == m->to) continue;
        append_segment(path, m->from + shift, m->to + shift, m->rapid, m->feed, line, operation);
      } else if (const auto* arc = std::get_if<gcode::ArcMove>(&a)) {
        const gcode::ArcChords chords = gcode::arc_chords(*arc, options.arc_tolerance);
        Vec3 p = arc->from;
        for (const Vec3& q : chords.points) {
          append_segment(path, p + shift, q + shift, false, chords.feed, line, operation);
          p = q;
        }
        ++path.arcs;
      } else if (const auto* pr = std::get_if<gcode::ProbeMove>(&a)) {
        append_segment(path, pr->from + shift, pr->to + shift, false, pr->feed, line, operation);
      }
      moved = true;
    }
    state = r.state;
  }
  colour_toolpath(path, PathColouring::Feed);
  return path;
}

PathColouring parse_path_colouring(const std::string& name) {
  if (name == "feed") return PathColouring::Feed;
  if (name == "operation") return PathColouring::Operation;
  std::string m = "unknown colouring '";
  m += name;
  m += "': use feed or operation";
  throw std::invalid_argument(m);
}

void colour_toolpath(Toolpath& path, PathColouring how) {
  const double span = path.max_feed - path.min_feed;
  for (std::size_t k = 0; k < path.segments.size(); ++k) {
    Rgb c = kRapidColour;
    if (!path.rapid(k)) {
      if (how == PathColouring::Operation) {
        c = category_colour(path.segments[k].operation);
      } else {
        // One feed only: the middle of the ramp.
        const double t = span > 0 ? (path.segments[k].feed - path.min_feed) / span : 0.5;
        c = colormap_viridis(t);
      }
    }
    for (std::size_t v = 2 * k; v < 2 * k + 2; ++v) {
      path.vertices[v].r = c.r;
      path.vertices[v].g = c.g;
      path.vertices[v].b = c.b;
    }
  }
}

}  // namespace cncstream::viewer
