// The job preview over HTTP: the height PNG (size, colours that follow the
// heights, bounds on the program's extent), the thinned path (its budget,
// its ends), bad sizes, unknown jobs, jobs without a program, the token.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "../cam/cl_test_meshes.hpp"
#include "cncstream/gcode/program.hpp"
#include "cncstream/geometry/stl.hpp"
#include "cncstream/image/image.hpp"
#include "daemon_test_util.hpp"

using namespace dtest;
using cncstream::image::Rgb;
using cncstream::geometry::Vec3;

namespace {

const std::string kClient = "preview-1";

Http with_client(Http h) {
  h.headers["X-Client-Id"] = kClient;
  return h;
}

json upload(const Http& h, const std::string& bytes, const std::string& name) {
  const auto r = h.request("POST", "/api/v1/files?name=" + name, bytes, {{"Content-Type", "application/octet-stream"}});
  EXPECT_TRUE(r.status == 201 || r.status == 200) << r.status << " " << r.body;
  return r.status == 201 || r.status == 200 ? r.j() : json();
}

json job(const Http& h, std::int64_t id) { return h.get("/api/v1/jobs/" + std::to_string(id)).j(); }

std::int64_t ready_job(const Http& h, const json& body) {
  const auto r = h.post("/api/v1/jobs", body);
  EXPECT_EQ(r.status, 201) << r.body;
  if (r.status != 201) return 0;
  const auto id = r.j()["id"].get<std::int64_t>();
  EXPECT_TRUE(wait_for([&] { return job(h, id)["state"] == "ready"; }, 120)) << job(h, id).dump();
  return id;
}

// A dome on a plate as binary STL bytes (centre at 10, 10; its top the highest point).
std::string dome_stl(const fs::path& dir) {
  const auto p = dir / "dome.stl";
  cncstream::geometry::write_stl_binary(p, cl_test::dome_on_plate(20, 8));
  return read_file(p);
}

// Rows along Y over [0, 30] x [0, 20] on a dome centred at (15, 12) (off the
// middle in Y: north up shows), rapids in and out.
double dome(double x, double y) { return 3 - ((x - 15) * (x - 15) + (y - 12) * (y - 12)) / 60; }
std::string dome_gcode() {
  std::string g = "G21 G90\nG0 Z5\nG0 X0 Y0\n";
  char b[96];
  std::snprintf(b, sizeof b, "G1 Z%.4f F300\n", dome(0, 0));
  g += b;
  for (int c = 0; c <= 30; ++c) {
    if (c > 0) {
      std::snprintf(b, sizeof b, "G1 X%d Z%.4f F1000\n", c, dome(c, c % 2 ? 20 : 0));
      g += b;
    }
    for (int k = 1; k <= 40; ++k) {
      const double y = c % 2 ? 20 - 0.5 * k : 0.5 * k;
      std::snprintf(b, sizeof b, "G1 Y%.4f Z%.4f\n", y, dome(c, y));
      g += b;
    }
  }
  return g + "G0 Z5\nG0 X-10 Y-10\nM2\n";
}

// The t in [0, 1] whose viridis colour is nearest to c.
double ramp_position(Rgb c) {
  double best = -1, dist = 1e9;
  for (int k = 0; k <= 255; ++k) {
    const Rgb v = cncstream::image::colormap_viridis(k / 255.0);
    const double d = std::hypot(v.r - c.r, v.g - c.g, v.b - c.b);
    if (d < dist) {
      dist = d;
      best = k / 255.0;
    }
  }
  return best;
}

struct Extent {
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9, z0 = 1e9, z1 = -1e9;
};
// The program's cutting moves' extent, work coordinates (as the daemon
// traces it); heights from the moves along the surface (a plunge's top is
// no cut).
Extent cut_extent(const cncstream::gcode::ProgramTrace& t) {
  Extent e;
  for (const auto& s : t.segments) {
    if (s.rapid) continue;
    const bool along = s.work_from().x != s.work_to().x || s.work_from().y != s.work_to().y;
    for (const Vec3& p : {s.work_from(), s.work_to()}) {
      e.x0 = std::min(e.x0, p.x);
      e.x1 = std::max(e.x1, p.x);
      e.y0 = std::min(e.y0, p.y);
      e.y1 = std::max(e.y1, p.y);
      if (!along) continue;
      e.z0 = std::min(e.z0, p.z);
      e.z1 = std::max(e.z1, p.z);
    }
  }
  return e;
}

struct Probe {
  double x, y, z;  // work coordinates: the tip's height there
};

// The PNG: a PNG of the size the bounds give whose colours give the heights
// back (at the probes; the first probe is the top: no pixel is much higher).
void check_png(const Http& h, const std::string& url, const json& preview, int long_side,
               const std::vector<Probe>& probes) {
  const auto r = h.get(url);
  ASSERT_EQ(r.status, 200) << r.body.substr(0, 300);
  EXPECT_EQ(r.headers.count("content-type") ? r.headers.at("content-type") : "", "image/png");
  const auto img = cncstream::image::decode_png(r.body);
  const auto& b = preview["bounds"];
  const double x0 = b[0].get<double>(), y1 = b[3].get<double>();
  const double ex = b[2].get<double>() - x0, ey = y1 - b[1].get<double>();
  const double z0 = preview["z"][0].get<double>(), z1 = preview["z"][1].get<double>();
  const int w = ex >= ey ? long_side : static_cast<int>(std::lround(long_side * ex / ey));
  const int hgt = ey >= ex ? long_side : static_cast<int>(std::lround(long_side * ey / ex));
  ASSERT_EQ(img.width(), w);
  ASSERT_EQ(img.height(), hgt);
  // Work coordinates to pixels: the bounds span the picture, north up.
  const auto px = [&](double x) { return std::clamp(static_cast<int>((x - x0) / ex * w), 0, w - 1); };
  const auto py = [&](double y) { return std::clamp(static_cast<int>((y1 - y) / ey * hgt), 0, hgt - 1); };
  for (const auto& p : probes)
    EXPECT_NEAR(ramp_position(img.get(px(p.x), py(p.y))), (p.z - z0) / (z1 - z0), 0.03)
        << "at " << p.x << ", " << p.y << " (z " << p.z << ") in " << url;
  const double top = ramp_position(img.get(px(probes[0].x), py(probes[0].y)));
  EXPECT_GT(top, 0.95) << "the top should be the top of the ramp";
  double highest = 0;
  for (int y = 0; y < img.height(); y += 3)
    for (int x = 0; x < img.width(); x += 3) highest = std::max(highest, ramp_position(img.get(x, y)));
  EXPECT_GE(top + 0.02, highest) << "no pixel is much higher than the top";
}

void check_path(const Http& h, const std::string& base, const cncstream::gcode::ProgramTrace& trace) {
  const Vec3 first = trace.segments.front().work_from(), last = trace.segments.back().work_to();
  for (int budget : {0, 50, 500}) {
    const auto r = h.get(base + "/path" + (budget ? "?max_points=" + std::to_string(budget) : std::string()));
    ASSERT_EQ(r.status, 200) << r.body.substr(0, 300);
    const json p = r.j();
    std::size_t n = 0;
    for (const char* kind : {"cuts", "rapids"})
      for (const auto& line : p[kind]) {
        EXPECT_EQ(line.size() % 3, 0u);
        EXPECT_GE(line.size(), 6u);  // a polyline has two points at least
        n += line.size() / 3;
      }
    EXPECT_EQ(n, p["points"].get<std::size_t>());
    EXPECT_LE(n, budget ? std::size_t(budget) : 20000u);
    EXPECT_GT(p["total_points"].get<std::size_t>(), 500u);  // more than the budgets: thinned
    ASSERT_FALSE(p["cuts"].empty());
    ASSERT_FALSE(p["rapids"].empty());
    // The path begins and ends with rapids here: the program's own first and last points.
    const auto& a = p["rapids"].front();
    const auto& z = p["rapids"].back();
    EXPECT_NEAR(a[0].get<double>(), first.x, 1e-3);
    EXPECT_NEAR(a[1].get<double>(), first.y, 1e-3);
    EXPECT_NEAR(a[2].get<double>(), first.z, 1e-3);
    const std::size_t k = z.size() - 3;
    EXPECT_NEAR(z[k].get<double>(), last.x, 1e-3);
    EXPECT_NEAR(z[k + 1].get<double>(), last.y, 1e-3);
    EXPECT_NEAR(z[k + 2].get<double>(), last.z, 1e-3);
  }
}

void check_bounds(const json& preview, const Extent& e, double z_tolerance) {
  const auto& b = preview["bounds"];
  EXPECT_NEAR(b[0].get<double>(), e.x0, 1e-3);
  EXPECT_NEAR(b[1].get<double>(), e.y0, 1e-3);
  EXPECT_NEAR(b[2].get<double>(), e.x1, 1e-3);
  EXPECT_NEAR(b[3].get<double>(), e.y1, 1e-3);
  EXPECT_NEAR(preview["z"][1].get<double>(), e.z1, z_tolerance);
  EXPECT_NEAR(preview["z"][0].get<double>(), e.z0, z_tolerance);
}

void check_bad_requests(const Http& h, const std::string& base) {
  for (const char* q : {"?max=8", "?max=1025", "?max=abc", "?max=", "?max=-5", "?max=12.5"}) {
    const auto r = h.get(base + "/clmap.png" + q);
    EXPECT_EQ(r.status, 400) << q;
    EXPECT_EQ(r.j()["error"]["code"], "bad_request") << q;
  }
  for (const char* q : {"?max_points=1", "?max_points=200001", "?max_points=x", "?max_points=99999999999999"})
    EXPECT_EQ(h.get(base + "/path" + q).status, 400) << q;
  for (const char* u : {"/api/v1/jobs/99999/clmap.png", "/api/v1/jobs/99999/path", "/api/v1/jobs/abc/path"}) {
    const auto r = h.get(u);
    EXPECT_EQ(r.status, 404) << u;
    EXPECT_EQ(r.j()["error"]["code"], "not_found") << u;
  }
}

}  // namespace

TEST(DaemonPreview, StlJobGivesItsClGridAsAPngAndItsPathThinned) {
  const auto dir = temp_dir("preview-stl");
  RunningDaemon d(test_config(dir));
  const Http h = with_client(d.http);
  const auto f = upload(h, dome_stl(dir), "dome.stl");
  const auto id = ready_job(h, {{"machine", "sim1"}, {"file", f["id"]}, {"params", {{"tool", "ball:3"}, {"stepover", 1}, {"stock", "none"}, {"strategy", "raster"}}}});
  ASSERT_GT(id, 0);
  const std::string base = "/api/v1/jobs/" + std::to_string(id);
  const json preview = job(h, id)["preview"];
  ASSERT_TRUE(preview.is_object()) << job(h, id).dump();
  EXPECT_EQ(preview["png"], base + "/clmap.png");
  EXPECT_EQ(preview["path"], base + "/path");
  const auto program = h.get(base + "/gcode");
  ASSERT_EQ(program.status, 200);
  const auto trace = cncstream::gcode::trace_program(program.body);
  const Extent e = cut_extent(trace);
  // The CL grid's range: the program's cuts sit on it (within the merge tolerance).
  check_bounds(preview, e, 0.01);
  // Work coordinates: X, Y from the part's corner, Z 0 on its top (model z 6),
  // so the dome's centre is at (10, 10). The ball (r 1.5) over the cap (a
  // sphere of r 8 centred at model z -2): its tip at -2 + sqrt(9.5^2 - d^2) - 1.5;
  // beyond the plate's grown corners it rests on the floor, the plate (z 2).
  const auto on_cap = [](double d) { return -2 + std::sqrt(9.5 * 9.5 - d * d) - 1.5 - 6; };
  const std::vector<Probe> probes = {{10, 10.5, on_cap(0.5)}, {10 - 5.75, 10.5, on_cap(std::hypot(5.75, 0.5))},
                                     {e.x0, e.y0, -4}, {e.x1, e.y0, -4}, {e.x0, e.y1, -4}, {e.x1, e.y1, -4}};
  check_png(h, base + "/clmap.png", preview, 1024, probes);
  check_png(h, base + "/clmap.png?max=200", preview, 200, probes);
  check_path(h, base, trace);
  check_bad_requests(h, base);
  d.shutdown();
  fs::remove_all(dir);
}

TEST(DaemonPreview, GcodeJobIsRasterisedFromItsCuttingMoves) {
  const auto dir = temp_dir("preview-gcode");
  RunningDaemon d(test_config(dir));
  const Http h = with_client(d.http);
  const std::string text = dome_gcode();
  const auto f = upload(h, text, "dome.nc");
  ASSERT_EQ(f["kind"], "gcode");
  const auto id = ready_job(h, {{"machine", "sim2"}, {"file", f["id"]}});
  ASSERT_GT(id, 0);
  const std::string base = "/api/v1/jobs/" + std::to_string(id);
  // Asked for before the trace after `ready` may be done: traced for the request.
  const auto early = h.get(base + "/clmap.png?max=64");
  EXPECT_EQ(early.status, 200) << early.body.substr(0, 300);
  ASSERT_TRUE(wait_for([&] { return job(h, id)["preview"].is_object(); }, 60)) << job(h, id).dump();
  const json preview = job(h, id)["preview"];
  const auto trace = cncstream::gcode::trace_program(text);
  const Extent e = cut_extent(trace);
  EXPECT_DOUBLE_EQ(e.x1, 30);
  check_bounds(preview, e, 1e-3);  // the rapid to (-10, -10) is no cut
  const std::vector<Probe> probes = {{15, 12, dome(15, 12)}, {7.5, 12, dome(7.5, 12)}, {0, 0, dome(0, 0)},
                                     {30, 0, dome(30, 0)},     {0, 20, dome(0, 20)},     {30, 20, dome(30, 20)}};
  check_png(h, base + "/clmap.png", preview, 1024, probes);
  check_png(h, base + "/clmap.png?max=300", preview, 300, probes);
  check_path(h, base, trace);
  check_bad_requests(h, base);
  d.shutdown();
  fs::remove_all(dir);
}

TEST(DaemonPreview, AJobWithoutAProgramIs409AndHasNoPreview) {
  const auto dir = temp_dir("preview-none");
  auto cfg = test_config(dir);
  std::int64_t id = 0;
  {
    RunningDaemon d(cfg);
    const Http h = with_client(d.http);
    const auto f = upload(h, dome_gcode(), "dome.nc");
    id = ready_job(h, {{"machine", "sim1"}, {"file", f["id"]}});
    ASSERT_GT(id, 0);
    ASSERT_EQ(h.post("/api/v1/machines/sim1/control").status, 200);
    ASSERT_EQ(h.post("/api/v1/jobs/" + std::to_string(id) + "/cancel").status, 200);
    d.shutdown();
  }
  // After a restart a finished job's program is not loaded again.
  RunningDaemon d(cfg);
  const Http h = with_client(d.http);
  const std::string base = "/api/v1/jobs/" + std::to_string(id);
  const json j = job(h, id);
  EXPECT_EQ(j["state"], "cancelled");
  EXPECT_TRUE(j["preview"].is_null());
  for (const char* route : {"/clmap.png", "/path"}) {
    const auto r = h.get(base + route);
    EXPECT_EQ(r.status, 409) << route;
    EXPECT_EQ(r.j()["error"]["code"], "bad_state") << route;
    EXPECT_NE(r.j()["error"]["message"].get<std::string>().find("no program"), std::string::npos) << r.body;
  }
  d.shutdown();
  fs::remove_all(dir);
}

TEST(DaemonPreview, PreviewRoutesNeedTheTokenLikeTheOtherGets) {
  const auto dir = temp_dir("preview-token");
  auto cfg = test_config(dir);
  cfg.security.require_token = true;
  RunningDaemon d(cfg);
  Http h = with_client(d.http);
  EXPECT_EQ(h.get("/api/v1/jobs/1/clmap.png").status, 401);
  EXPECT_EQ(h.get("/api/v1/jobs/1/path").status, 401);
  h.headers["Authorization"] = "Bearer " + d.daemon().token();
  EXPECT_EQ(h.get("/api/v1/jobs/1/clmap.png").status, 404);
  d.shutdown();
  fs::remove_all(dir);
}
