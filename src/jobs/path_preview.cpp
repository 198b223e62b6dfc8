// A program's path thinned for drawing.
#include "cncstream/jobs/path_preview.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace cncstream::jobs {

namespace {

enum Span : std::uint8_t { kRapid = 0, kCut = 1, kJump = 2 };

double distance_to_segment(const geometry::Vec3& p, const geometry::Vec3& a, const geometry::Vec3& b) {
  const geometry::Vec3 ab = b - a, ap = p - a;
  const double l2 = dot(ab, ab);
  const double t = l2 > 0 ? std::clamp(dot(ap, ab) / l2, 0.0, 1.0) : 0.0;
  return norm(ap - ab * t);
}

// Douglas-Peucker without a tolerance: each point gets the distance at which
// it would be split off (never more than its parent's), so keeping the k most
// important points is the simplification with k points.
std::vector<double> importance(const std::vector<geometry::Vec3>& p) {
  const std::size_t n = p.size();
  std::vector<double> imp(n, 0.0);
  imp.front() = imp.back() = std::numeric_limits<double>::infinity();
  struct Todo {
    std::size_t a, b;
    double cap;
  };
  std::vector<Todo> stack{{0, n - 1, std::numeric_limits<double>::infinity()}};
  while (!stack.empty()) {
    const Todo t = stack.back();
    stack.pop_back();
    if (t.b - t.a < 2) continue;
    std::size_t best = t.a + 1;
    double d = -1;
    for (std::size_t k = t.a + 1; k < t.b; ++k)
      if (const double dk = distance_to_segment(p[k], p[t.a], p[t.b]); dk > d) {
        d = dk;
        best = k;
      }
    const double v = std::min(d, t.cap);
    imp[best] = v;
    stack.push_back({t.a, best, v});
    stack.push_back({best, t.b, v});
  }
  return imp;
}

}  // namespace

PathPreview decimate_path(const gcode::ProgramTrace& trace, std::size_t max_points) {
  if (max_points < 2) throw std::invalid_argument("path preview: max_points must be at least 2");
  // The path as one chain of points; span[k] joins pts[k] and pts[k+1].
  std::vector<geometry::Vec3> pts;
  std::vector<std::uint8_t> span;
  for (const auto& s : trace.segments) {
    const geometry::Vec3 a = s.work_from(), b = s.work_to();
    if (pts.empty()) {
      pts.push_back(a);
    } else if (norm(pts.back() - a) > 1e-9) {
      span.push_back(kJump);  // the work offset moved under the tool
      pts.push_back(a);
    }
    if (b == a) continue;
    span.push_back(s.rapid ? kRapid : kCut);
    pts.push_back(b);
  }
  PathPreview out;
  out.total_points = pts.size();
  if (pts.empty()) return out;
  const std::size_t n = pts.size();
  if (n == 1) {  // only moves that go nowhere
    out.rapids.push_back({pts[0]});
    out.points = 1;
    return out;
  }

  // Where a move changes kind ranks above any shape point, a jump's ends above that.
  std::vector<double> imp = importance(pts);
  for (std::size_t k = 1; k + 1 < n; ++k) {
    if (span[k - 1] == kJump || span[k] == kJump) imp[k] += 2e12;
    else if (span[k - 1] != span[k]) imp[k] += 1e12;
  }
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return imp[a] > imp[b]; });
  // Prefix counts: what a span between two kept points contains.
  std::vector<std::size_t> cuts(n, 0), jumps(n, 0);
  for (std::size_t k = 0; k + 1 < n; ++k) {
    cuts[k + 1] = cuts[k] + (span[k] == kCut);
    jumps[k + 1] = jumps[k] + (span[k] == kJump);
  }
  std::vector<std::uint8_t> keep(n, 0);
  // Walks the kept points in order, calling emit(kind, a, b) per drawn span;
  // returns the points the polylines take (a point where two meet, twice).
  const auto walk = [&](auto&& emit) {
    std::size_t count = 0, prev = 0;
    int run = -1;  // the kind of the polyline being drawn, -1: none
    for (std::size_t k = 1; k < n; ++k) {
      if (!keep[k]) continue;
      const int kind = jumps[k] > jumps[prev] ? kJump : cuts[k] > cuts[prev] ? kCut : kRapid;
      if (kind == kJump) {
        run = -1;
      } else {
        count += kind == run ? 1 : 2;
        emit(kind, prev, k, kind != run);
        run = kind;
      }
      prev = k;
    }
    return count;
  };
  const auto count_with = [&](std::size_t top) {
    std::fill(keep.begin(), keep.end(), 0);
    for (std::size_t r = 0; r < top; ++r) keep[order[r]] = 1;
    return walk([](int, std::size_t, std::size_t, bool) {});
  };
  // The most points that fit (the count grows with them, give or take a kind change).
  std::size_t lo = 2, hi = n;
  while (lo < hi) {
    const std::size_t mid = lo + (hi - lo + 1) / 2;
    if (count_with(mid) <= max_points) lo = mid;
    else hi = mid - 1;
  }
  while (lo > 2 && count_with(lo) > max_points) --lo;
  count_with(lo);
  out.points = walk([&](int kind, std::size_t a, std::size_t b, bool fresh) {
    auto& list = kind == kCut ? out.cuts : out.rapids;
    if (fresh) list.push_back({pts[a]});
    list.back().push_back(pts[b]);
  });
  return out;
}

}  // namespace cncstream::jobs
