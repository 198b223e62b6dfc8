// The viewer's scene and its timeline arithmetic (see scene.hpp).
#include "cncstream/viewer/scene.hpp"

#include <algorithm>

#include <fmt/core.h>

namespace cncstream::viewer {

geometry::Box3 Scene::bounds() const {
  geometry::Box3 b;
  auto add = [&](const geometry::Box3& o) {
    if (!o.empty()) b.add(o.lo), b.add(o.hi);
  };
  if (part) add(part->bounds);
  if (cut) add(cut->mesh.bounds);
  if (program) add(program->bounds);
  if (const auto tip = cutter_tip()) {
    b.add(*tip);
    b.add(*tip + geometry::Vec3{cutter->radius, cutter->radius, default_cutter_length(*cutter)});
    b.add(*tip - geometry::Vec3{cutter->radius, cutter->radius, 0});
  }
  return b;
}

std::optional<geometry::Vec3> Scene::cutter_tip() const {
  if (!cutter) return std::nullopt;
  if (cutter_at) return cutter_at;
  if (program && program->size() > 0)
    return program->point_at(std::isnan(progress) ? static_cast<double>(program->size()) : progress);
  return geometry::Vec3{};
}

double timeline_step(const Scene& scene, double direction) {
  if (!scene.program || scene.program->size() == 0) return NAN;
  const auto n = static_cast<double>(scene.program->size());
  const double at = std::isnan(scene.progress) ? n : scene.progress;
  const double step = std::max(1.0, std::floor(n / 500));
  return std::clamp(at + direction * step, 0.0, n);
}

double timeline_at_bar(double x, int bar_x, int bar_w, std::size_t segments) {
  const double f = std::clamp((x - bar_x) / std::max(bar_w, 1), 0.0, 1.0);
  return f * static_cast<double>(segments);
}

std::string format_position(const geometry::Vec3& p) { return fmt::format("X {:.3f} Y {:.3f} Z {:.3f}", p.x, p.y, p.z); }

std::string format_progress(const Toolpath& path, double progress) {
  if (path.size() == 0) return "no moves";
  const auto n = path.size();
  const double t = std::isnan(progress) ? static_cast<double>(n) : std::clamp(progress, 0.0, static_cast<double>(n));
  const auto k = std::min(static_cast<std::size_t>(t), n - 1);
  return fmt::format("segment {} of {}, line {}", static_cast<std::size_t>(t), n, path.segments[k].line + 1);
}

}  // namespace cncstream::viewer
