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

geometry::Vec3 Toolpath::point_at(double t) const {
  if (segments.empty()) return {};
  const double n = static_cast<double>(segments.size());
  t = std::clamp(t, 0.0, n);
  if (t >= n) return to(segments.size() - 1);
  const auto k = static_cast<std::size_t>(t);
  const double f = t - static_cast<double>(k);
  return from(k) + (to(k) - from(k)) * f;
}

std::uint32_t Toolpath::vertices_done(double t) const {
  if (segments.empty() || !(t >= 1)) return 0;
  const auto k = std::min(static_cast<std::size_t>(t), segments.size());
  return segments[k - 1].vertex + 1;
}

void append_segment(Toolpath& path, const geometry::Vec3& from, const geometry::Vec3& to, bool rapid, double feed, std::uint32_t line,
                    std::uint32_t operation) {
  const PathVertex a{static_cast<float>(from.x), static_cast<float>(from.y), static_cast<float>(from.z), 0, 0, 0, 0,
                     kJump};
  PathVertex b{static_cast<float>(to.x), static_cast<float>(to.y), static_cast<float>(to.z), 0, 0, 0, 0,
               rapid ? kRapid : kCut};
  const bool meets = !path.vertices.empty() && path.vertices.back().x == a.x && path.vertices.back().y == a.y &&
                     path.vertices.back().z == a.z;
  if (!meets) path.vertices.push_back(a);  // the first point, or a hidden jump to it
  if (rapid) {
    // The dash pattern runs on along consecutive rapids.
    b.along = path.vertices.back().along + static_cast<float>(norm(to - from));
    ++path.rapids;
  } else {
    if (path.segments.size() == path.rapids) path.min_feed = path.max_feed = feed;  // the first cut
    path.min_feed = std::min(path.min_feed, feed);
    path.max_feed = std::max(path.max_feed, feed);
  }
  path.vertices.push_back(b);
  path.segments.push_back({static_cast<float>(rapid ? 0.0 : feed), line, operation,
                           static_cast<std::uint32_t>(path.vertices.size() - 1)});
  path.bounds.add(from);
  path.bounds.add(to);
}

Toolpath build_toolpath(std::string_view program, const ToolpathOptions& options) {
  Toolpath path;
  gcode::ParserState state = options.initial;
  const auto lines = gcode::split_lines(program);
  path.lines = lines.size();
  // About one move a line: growing 5 million-entry vectors by copying cost
  // a fifth of the load.
  path.vertices.reserve(lines.size() + 2);
  path.segments.reserve(lines.size());
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
    const geometry::Vec3 shift = options.offset - r.state.wco();
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
        geometry::Vec3 p = arc->from;
        for (const geometry::Vec3& q : chords.points) {
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
    image::Rgb c = kRapidColour;
    if (!path.rapid(k)) {
      if (how == PathColouring::Operation) {
        c = image::category_colour(path.segments[k].operation);
      } else {
        // One feed only: the middle of the ramp.
        const double t = span > 0 ? (path.segments[k].feed - path.min_feed) / span : 0.5;
        c = image::colormap_viridis(t);
      }
    }
    PathVertex& v = path.vertices[path.segments[k].vertex];
    v.r = c.r;
    v.g = c.g;
    v.b = c.b;
  }
}

std::vector<std::uint32_t> display_strip(const Toolpath& path, double tolerance) {
  std::vector<std::uint32_t> keep;
  const std::size_t n = path.vertices.size();
  if (n == 0) return keep;
  keep.reserve(n / 4 + 2);
  auto pos = [&](std::size_t v) {
    const PathVertex& p = path.vertices[v];
    return geometry::Vec3{p.x, p.y, p.z};
  };
  auto same_look = [&](std::size_t u, std::size_t v) {
    const PathVertex &a = path.vertices[u], &b = path.vertices[v];
    return a.kind == b.kind && a.kind != kJump && a.r == b.r && a.g == b.g && a.b == b.b;
  };
  // Squared distance of p from the segment a-b.
  auto dist2 = [](const geometry::Vec3& p, const geometry::Vec3& a, const geometry::Vec3& b) {
    const geometry::Vec3 ab = b - a;
    const double l2 = dot(ab, ab);
    const double t = l2 > 0 ? std::clamp(dot(p - a, ab) / l2, 0.0, 1.0) : 0.0;
    const geometry::Vec3 d = p - (a + ab * t);
    return dot(d, d);
  };
  const double tol2 = tolerance * tolerance;
  constexpr std::size_t kMaxRun = 64;  // bounds the checks per kept vertex
  std::size_t anchor = 0;
  keep.push_back(0);
  for (std::size_t v = 1; v < n; ++v) {
    // Can the line anchor -> v + 1 replace the lines through v?
    // (The lines before v in the run already look like the one ending at v.)
    bool merge = v + 1 < n && v + 1 - anchor <= kMaxRun && same_look(v, v + 1);
    if (merge) {
      const geometry::Vec3 a = pos(anchor), b = pos(v + 1);
      for (std::size_t u = anchor + 1; u <= v && merge; ++u) merge = dist2(pos(u), a, b) <= tol2;
    }
    if (!merge) {
      keep.push_back(static_cast<std::uint32_t>(v));
      anchor = v;
    }
  }
  return keep;
}

}  // namespace cncstream::viewer
