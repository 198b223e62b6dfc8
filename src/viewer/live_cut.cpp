// The live job's removed material (see live_cut.hpp).
#include "cncstream/viewer/live_cut.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>
#include <string>

#include "cncstream/gcode/job_program.hpp"

namespace cncstream::viewer {

namespace {

std::vector<std::string_view> split_lines(std::string_view text) {
  std::vector<std::string_view> lines;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(pos, end - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    lines.push_back(line);
    pos = end + 1;
  }
  return lines;
}

// Reads a number at `pos` in `text` and moves past it; false when none is there.
bool read_number(std::string_view text, std::size_t& pos, double& value) {
  if (pos >= text.size()) return false;
  const auto r = std::from_chars(text.data() + pos, text.data() + text.size(), value);
  if (r.ec != std::errc() || !std::isfinite(value)) return false;
  pos = static_cast<std::size_t>(r.ptr - text.data());
  return true;
}

bool expect(std::string_view text, std::size_t& pos, std::string_view what) {
  if (text.substr(pos, what.size()) != what) return false;
  pos += what.size();
  return true;
}

cam::HeightFieldStock make_stock(const Toolpath& path, const std::vector<MountedCutter>& cutters,
                            std::optional<geometry::Box3> block, const LiveCutOptions& options) {
  if (cutters.empty()) throw std::invalid_argument("viewer: the live cut needs the cutter the program runs with");
  if (!block) {
    double reach = 0;
    for (const auto& c : cutters) reach = std::max(reach, c.cutter.radius);
    geometry::Box3 moves;
    double top = -HUGE_VAL;
    bool from_z0 = false;
    for (std::size_t k = 0; k < path.size(); ++k) {
      if (path.vertices[path.segments[k].vertex].kind != kCut) continue;
      const geometry::Vec3 a = path.from(k), b = path.to(k);
      moves.add(a);
      moves.add(b);
      if (a.x != b.x || a.y != b.y) top = std::max({top, a.z, b.z});
      from_z0 = from_z0 || std::max(a.z, b.z) >= options.work_z0;
    }
    if (moves.empty()) throw std::invalid_argument("viewer: the program has no cutting move to show the cut of");
    if (from_z0) top = std::max(top, options.work_z0);
    if (!std::isfinite(top)) top = moves.hi.z;  // plunges only
    block = geometry::Box3{moves.lo - geometry::Vec3{reach, reach, 0}, geometry::Vec3{moves.hi.x + reach, moves.hi.y + reach, top}};
  }
  const geometry::Vec3 size = block->size();
  if (!(size.x > 0 && size.y > 0))
    throw std::invalid_argument("viewer: the stock for the live cut has no extent in X or Y");
  const double step =
      std::max(options.min_step, std::sqrt(size.x * size.y / static_cast<double>(std::max<std::size_t>(options.max_nodes, 4))));
  const cam::GridSpec grid = cam::GridSpec::covering(block->lo.x, block->lo.y, block->hi.x, block->hi.y, step, step);
  return cam::HeightFieldStock(grid, block->hi.z);
}

}  // namespace

std::vector<MountedCutter> program_cutters(std::string_view program) {
  std::vector<MountedCutter> out;
  for (const auto& op : program_operations(split_lines(program))) {
    const auto lb = op.cutter.rfind('['), rb = op.cutter.rfind(']');
    if (lb == std::string::npos || rb == std::string::npos || rb < lb) continue;
    try {
      out.push_back({op.mounted_line > 0 ? op.mounted_line - 1 : 0,
                     cam::parse_cutter_spec(std::string_view(op.cutter).substr(lb + 1, rb - lb - 1))});
    } catch (const std::invalid_argument&) {
      // Not a cutter we know: the operation cuts nothing in the view.
    }
  }
  return out;
}

std::optional<geometry::Box3> program_stock(std::string_view program) {
  // JobProgram's header: "(stock: X -1.000..121.000 Y -1.000..101.000 Z -10.500..1.000 [work coordinates])".
  const std::size_t at = program.substr(0, 8192).find("(stock: X ");
  if (at == std::string_view::npos) return std::nullopt;
  std::size_t pos = at + 10;
  double v[6];
  const bool ok = read_number(program, pos, v[0]) && expect(program, pos, "..") && read_number(program, pos, v[3]) &&
                  expect(program, pos, " Y ") && read_number(program, pos, v[1]) && expect(program, pos, "..") &&
                  read_number(program, pos, v[4]) && expect(program, pos, " Z ") && read_number(program, pos, v[2]) &&
                  expect(program, pos, "..") && read_number(program, pos, v[5]);
  if (!ok || !(v[0] < v[3] && v[1] < v[4] && v[2] < v[5])) return std::nullopt;
  return geometry::Box3{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}};
}

LiveCut::LiveCut(const Toolpath& path, std::vector<MountedCutter> cutters, std::optional<geometry::Box3> stock,
                 const LiveCutOptions& options)
    : path_(path), cutters_(std::move(cutters)), stock_(make_stock(path, cutters_, stock, options)) {
  std::stable_sort(cutters_.begin(), cutters_.end(),
                   [](const MountedCutter& a, const MountedCutter& b) { return a.line < b.line; });
}

std::size_t LiveCut::advance(double segments_done, std::size_t max_segments) {
  if (!(segments_done > 0)) return 0;
  const std::size_t upto =
      std::min(path_.size(), static_cast<std::size_t>(std::min(segments_done, static_cast<double>(path_.size()))));
  std::size_t count = 0;
  auto mount_for = [&](std::size_t segment) {
    while (mounted_ + 1 < cutters_.size() && cutters_[mounted_ + 1].line <= path_.segments[segment].line) ++mounted_;
  };
  for (; next_ < upto && count < max_segments; ++next_, ++count) {
    mount_for(next_);
    if (path_.vertices[path_.segments[next_].vertex].kind == kJump) continue;  // a work offset changed: no move
    stock_.cut_segment(path_.from(next_), path_.to(next_), cutters_[mounted_].cutter);
  }
  if (next_ < path_.size()) mount_for(next_);
  return count;
}

std::vector<float> LiveCut::heights() const {
  const auto& z = stock_.heights();
  return {z.begin(), z.end()};
}

}  // namespace cncstream::viewer
