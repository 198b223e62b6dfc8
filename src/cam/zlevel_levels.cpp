// The levels of Z-level roughing: every step_down from the stock top, the
// lowest tip height, and the heights of the part's flat areas.
#include <algorithm>
#include <cmath>
#include <vector>

#include "cncstream/cam/zlevel_roughing.hpp"

namespace cncstream::cam {

LevelPlan plan_levels(const std::vector<double>& tips, const std::vector<double>& flat_tips, double cell_area,
                      double stock_top, const RoughingParams& p, double min_flat_area) {
  std::vector<double> z;
  z.reserve(tips.size());
  for (double t : tips)
    if (std::isfinite(t)) z.push_back(t);
  LevelPlan plan;
  if (z.empty()) return plan;
  std::sort(z.begin(), z.end());
  double bottom = z.front();
  if (p.bottom) bottom = std::max(bottom, *p.bottom);
  if (!(bottom < stock_top)) return plan;

  std::vector<std::pair<double, bool>> levels;
  for (int k = 1;; ++k) {
    const double zk = stock_top - k * p.step_down;
    if (!(zk > bottom + 1e-9)) break;
    levels.emplace_back(zk, false);
  }
  levels.emplace_back(bottom, false);

  if (p.flat_levels) {
    // A flat area: at least min_flat_area of tip heights within flat_tol;
    // its level is the highest of them, so the whole flat is cut to within
    // flat_tol above.
    const double flat_tol = p.tolerance / 5;
    const auto need = static_cast<std::size_t>(std::ceil(min_flat_area / cell_area));
    std::vector<double> flats;
    z.clear();
    for (double t : flat_tips)
      if (std::isfinite(t)) z.push_back(t);
    std::sort(z.begin(), z.end());
    for (std::size_t i = 0, j = 0; i < z.size();) {
      j = std::max(j, i);
      while (j + 1 < z.size() && z[j + 1] - z[i] <= flat_tol) ++j;
      if (j - i + 1 >= std::max<std::size_t>(need, 1)) {
        flats.push_back(z[j]);
        i = j + 1;
      } else {
        ++i;
      }
    }
    for (double f : flats) {
      if (!(f < stock_top - 1e-9) || f < bottom) continue;
      // A level at most flat_tol above already cuts it.
      const bool covered = std::any_of(levels.begin(), levels.end(), [&](const auto& l) {
        return l.first >= f - 1e-12 && l.first <= f + flat_tol;
      });
      if (!covered) levels.emplace_back(f, true);
    }
  }
  std::sort(levels.begin(), levels.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  for (const auto& [zl, flat] : levels) {
    if (!plan.z.empty() && plan.z.back() - zl < 1e-9) continue;
    plan.z.push_back(zl);
    plan.flat.push_back(flat);
  }
  return plan;
}

}  // namespace cncstream::cam
