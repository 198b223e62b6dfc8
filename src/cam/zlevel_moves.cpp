// Z-level roughing as the moves the tool makes; see zlevel_roughing.hpp.
#include "cncstream/cam/zlevel_roughing.hpp"

#include <algorithm>

namespace cncstream::cam {

Polyline roughing_moves(const RoughingPath& path) {
  Polyline out;
  for (const auto& lv : path.levels)
    for (const auto& ps : lv.passes) {
      if (ps.points.empty()) continue;
      const geometry::Vec3& first = ps.points.front();
      if (out.empty()) {
        out.push_back({first.x, first.y, path.clearance_z});
      } else if (ps.lift_before) {
        // As the G-code lifts: up unless already higher, across, down.
        const geometry::Vec3 at = out.back();
        const double over = std::max(at.z, ps.lift_z);
        out.push_back({at.x, at.y, over});
        out.push_back({first.x, first.y, over});
      }
      out.insert(out.end(), ps.points.begin(), ps.points.end());
    }
  if (!out.empty()) out.push_back({out.back().x, out.back().y, std::max(out.back().z, path.clearance_z)});
  return out;
}

}  // namespace cncstream::cam
