// `cncstream view` end to end: a screenshot without a window (EGL, no X) of
// the plaque with a program placed by its header's work origin, the errors a
// person meets first, and the window following a job on the daemon.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include <chrono>
#include <thread>

#include "app_run.hpp"
#include "daemon_process.hpp"
#include "support/loopback_http.hpp"
#include "support/private_x_server.hpp"
#include "support/slot_program.hpp"
#include "cncstream/cam/deviation.hpp"
#include "cncstream/cam/height_field_io.hpp"
#include "cncstream/geometry/stl.hpp"
#include "cncstream/image/deviation_map.hpp"
#include "cncstream/image/image.hpp"

using namespace apptest;

namespace {

// Sets (or, with nullptr, unsets) an environment variable for the test's
// life (the child inherits it).
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* v = std::getenv(name)) saved_ = v;
    if (value) {
      ::setenv(name, value, 1);
    } else {
      ::unsetenv(name);
    }
  }
  ~ScopedEnv() {
    if (saved_) {
      ::setenv(name_, saved_->c_str(), 1);
    } else {
      ::unsetenv(name_);
    }
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  const char* name_;
  std::optional<std::string> saved_;
};

// Mesa's llvmpipe keeps blocks its JIT allocated to the end, which no leak
// suppression can name (the GL and viewer tests run without the leak check
// too): the rendering child runs without it.
constexpr const char* kRenderChildAsan = "detect_leaks=0:abort_on_error=1";

// The number after `label` in `text` (NaN when it is not there).
double number_after(const std::string& text, const std::string& label) {
  const auto at = text.find(label);
  return at == std::string::npos ? NAN : std::atof(text.c_str() + at + label.size());
}

}  // namespace

TEST(ViewCommand, ScreenshotOfThePlaqueAndItsProgramWithoutAWindow) {
  const fs::path nc = temp_dir() / "view_rows.nc";
  {
    std::ofstream f(nc);
    f << "(work origin: XY at part minimum, Z0 at part top)\nG21 G90 G17\nG0 Z5\nG0 X10 Y10\nG1 Z-1 F300\n"
         "G1 X110 F1200\nG2 X110 Y30 I0 J10\nG1 X10\nG0 Z5\n";
  }
  const fs::path png = temp_dir() / "view_top.png";
  const ScopedEnv no_display("DISPLAY", nullptr);  // no X is needed
  const ScopedEnv asan("ASAN_OPTIONS", kRenderChildAsan);
  const auto r = run_cncstream({"view", plaque(), "--program", nc.string(), "--cutter", "ball:3.175", "--screenshot",
                                png.string(), "--view", "top", "--size", "160x120"});
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(r.has("placed on the part by its work origin: offset X 0.000 Y 0.000 Z 10.500")) << r.out;
  EXPECT_TRUE(r.has("segments (3 rapid), 1 arc, 1 operation")) << r.out;
  EXPECT_TRUE(r.has("screenshot")) << r.out;
  const cncstream::image::RgbImage img = cncstream::image::read_png(png);
  ASSERT_EQ(img.width(), 160);
  ASSERT_EQ(img.height(), 120);
  int drawn = 0;
  for (int y = 0; y < img.height(); ++y)
    for (int x = 0; x < img.width(); ++x) drawn += !(img.get(x, y) == cncstream::image::Rgb{245, 246, 248});
  EXPECT_GT(drawn, 160 * 120 / 3);  // the plaque fills the fitted view
}

TEST(ViewCommand, WithoutADisplayItSaysSoAndSuggestsAScreenshot) {
  const ScopedEnv no_display("DISPLAY", nullptr), no_wayland("WAYLAND_DISPLAY", nullptr);
  const auto r = run_cncstream({"view", plaque()});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.has("no display")) << r.out;
  EXPECT_TRUE(r.has("--screenshot OUT.png")) << r.out;
}

TEST(ViewCommand, BadInputIsAClearError) {
  auto r = run_cncstream({"view"});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.has("nothing to show")) << r.out;
  r = run_cncstream({"view", plaque(), "--at", "1,2,3"});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.has("--at places the cutter")) << r.out;
  r = run_cncstream({"view", "--cutter", "ball:6", "--at", "1,2", "--screenshot", (temp_dir() / "x.png").string()});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.has("expected X,Y,Z")) << r.out;
  r = run_cncstream({"view", plaque(), "--screenshot", (temp_dir() / "x.png").string(), "--size", "0x10"});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.has("WIDTHxHEIGHT")) << r.out;
  r = run_cncstream({"view", "--follow", "sim1", "--program", "x.nc"});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.has("--follow takes the program and the cut from the daemon's job")) << r.out;
  r = run_cncstream({"view", plaque(), "--until-done"});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.has("go with --follow MACHINE")) << r.out;
  // No daemon there: the address in the message.
  r = run_cncstream({"view", "--follow", "sim1", "--daemon", "http://127.0.0.1:1", "--screenshot",
                     (temp_dir() / "x.png").string()});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.has("127.0.0.1:1")) << r.out;
}

TEST(ViewCommand, CutScreenshotCarriesTheDeviationMapsLegend) {
  // A clean cut of the plaque: its design heights on a 2 mm grid.
  const cncstream::geometry::Mesh plaque_mesh = cncstream::geometry::load_stl(plaque()).mesh;
  const cncstream::cam::GridSpec g = cncstream::cam::GridSpec::covering(0, 0, 120, 100, 2, 2);
  const cncstream::cam::DesignHeights d = cncstream::cam::design_heights(plaque_mesh, g);
  std::vector<double> z(g.size());
  for (std::size_t k = 0; k < g.size(); ++k) z[k] = d.off_part[k] ? plaque_mesh.bounds().lo.z : d.z[k];
  const fs::path cut = temp_dir() / "view_cut.f32";
  cncstream::cam::write_height_field(cut, g, z);
  const fs::path png = temp_dir() / "view_cut.png";
  const ScopedEnv asan("ASAN_OPTIONS", kRenderChildAsan);
  const auto r = run_cncstream({"view", "--cut", cut.string(), "--design", plaque(), "--screenshot", png.string(),
                                "--view", "top", "--size", "1000x640"});
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(r.has("61 x 51 nodes")) << r.out;
  EXPECT_TRUE(r.has(", 0 gouged,")) << r.out;
  const cncstream::image::RgbImage img = cncstream::image::read_png(png);
  ASSERT_EQ(img.width(), 1000);
  // The legend's swatches, in the map's own colours, right of the view.
  bool gouge_swatch = false, excess_swatch = false;
  for (int y = 0; y < img.height(); ++y)
    for (int x = img.width() / 2; x < img.width(); ++x) {
      gouge_swatch = gouge_swatch || img.get(x, y) == cncstream::image::DeviationPalette::gouge(0.6);
      excess_swatch = excess_swatch || img.get(x, y) == cncstream::image::DeviationPalette::excess(0.6);
    }
  EXPECT_TRUE(gouge_swatch);
  EXPECT_TRUE(excess_swatch);

  // The same cut as the job's simulator writes it: in work coordinates (Z0
  // at the part's top), saying where the model sat. It is placed on the
  // design, not compared 10.5 mm below it.
  const double top = plaque_mesh.bounds().hi.z;
  std::vector<double> work(z);
  for (double& h : work) h -= top;
  cncstream::cam::write_height_field(cut, g, work, cncstream::geometry::Vec3{0, 0, -top});
  const auto w = run_cncstream({"view", "--cut", cut.string(), "--design", plaque(), "--screenshot", png.string(),
                                "--view", "top", "--size", "320x200"});
  ASSERT_EQ(w.code, 0) << w.out;
  EXPECT_TRUE(w.has("cut placed on the design by its work origin: offset X 0.000 Y 0.000 Z 10.500")) << w.out;
  EXPECT_TRUE(w.has(", 0 gouged,")) << w.out;
}

// The window attached to a job on the daemon: it waits for the start, shows
// the tool change's pause, follows to the end (--until-done closes it) and
// has cut the slot's volume; then one frame of the finished job.
TEST(ViewFollow, TheWindowFollowsADaemonJobThroughItsToolChangeToItsEnd) {
  const PrivateXServer x;
  ASSERT_FALSE(x.display().empty()) << "Xvfb did not start (scripts/setup.sh installs xvfb)";
  const ScopedEnv display("DISPLAY", x.display().c_str());
  const ScopedEnv asan("ASAN_OPTIONS", kRenderChildAsan);
  DaemonProcess daemon({"--listen", "127.0.0.1:0", "--data", (temp_dir() / "follow-data").string(), "--machine",
                        "sim1=sim,sim_speed=5"});
  const unsigned short port = daemon.listen_port();
  ASSERT_NE(port, 0) << daemon.log();
  loopback::Http h;
  h.port = port;
  h.headers["X-Client-Id"] = "follow-test";
  auto wait = [](const std::function<bool()>& ok, double timeout_s) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (!ok() && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    return ok();
  };
  ASSERT_TRUE(wait([&] { return h.get("/api/v1/machines/sim1").j().value("link", "") == "ready"; }, 30)) << daemon.log();
  const auto file = h.request("POST", "/api/v1/files?name=slot.nc", testparts::kSlotProgram,
                              {{"Content-Type", "application/octet-stream"}});
  ASSERT_EQ(file.status, 201) << file.body;
  const auto created = h.post("/api/v1/jobs", {{"machine", "sim1"}, {"file", file.j()["id"]}});
  ASSERT_EQ(created.status, 201) << created.body;
  const std::string id = std::to_string(created.j()["id"].get<long>());
  const std::string job = "/api/v1/jobs/" + id;
  ASSERT_TRUE(wait([&] { return h.get(job).j()["state"] == "ready"; }, 30)) << h.get(job).body;
  ASSERT_EQ(h.post("/api/v1/machines/sim1/control").status, 200);
  const std::string api = "http://127.0.0.1:" + std::to_string(port);

  BackgroundProgram view("cncstream", {"view", "--follow", "sim1", "--daemon", api, "--until-done", "--size", "320x240"},
                         "state");
  ASSERT_TRUE(view.wait_output("following job " + id + " on sim1", 60)) << view.log();
  EXPECT_TRUE(view.wait_output("stock 601 x 401 nodes at 0.050 mm", 10)) << view.log();
  ASSERT_EQ(h.post(job + "/start").status, 202);
  EXPECT_TRUE(view.wait_output("job " + id + " running", 30)) << view.log();
  // The tool change, run by the machine's routine (manual: the operator
  // mounts, zeroes and confirms), in the viewer; the confirm goes on.
  ASSERT_TRUE(view.wait_output("tool change at line 16 (T1 -> T2, manual): mount T2", 30)) << view.log() << daemon.log();
  ASSERT_EQ(h.post("/api/v1/machines/sim1/tool-change/confirm").status, 202) << daemon.log();
  ASSERT_EQ(view.wait_exit(60), 0) << view.log();
  const std::string out = view.log();
  EXPECT_NE(out.find("job " + id + " done, line 19 of 19"), std::string::npos) << out;
  const std::string done = "job " + id + " done: ";
  ASSERT_NE(out.find(done), std::string::npos) << out;
  const std::string summary = out.substr(out.find(done));
  EXPECT_EQ(summary.find(done + "6 of 6 segments run"), 0u) << summary;
  const double slot = (10 * 6 + M_PI * 9) * 2;  // the 6 mm flat's slot, 10 mm long and 2 mm deep
  EXPECT_NEAR(number_after(summary, "segments run, "), slot, 0.03 * slot) << summary;

  // One frame of the finished job, without a window: the stock with its slot.
  const ScopedEnv no_display("DISPLAY", nullptr);
  const fs::path png = temp_dir() / "follow.png";
  const auto r = run_cncstream({"view", "--follow", "sim1", "--daemon", api, "--job", id, "--screenshot", png.string(),
                                "--size", "320x240"});
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NEAR(number_after(r.out, done + "6 of 6 segments run, "), slot, 0.03 * slot) << r.out;
  const cncstream::image::RgbImage img = cncstream::image::read_png(png);
  int stock = 0;
  for (int yy = 0; yy < img.height(); ++yy)
    for (int xx = 0; xx < img.width(); ++xx) {
      const auto c = img.get(xx, yy);
      stock += c.r > c.b + 30 && c.g > c.b + 10;  // the stock's warm colour, shaded
    }
  EXPECT_GT(stock, 320 * 240 / 10);
  // Following a machine without a job says so.
  const auto none = run_cncstream({"view", "--follow", "sim1", "--daemon", api, "--screenshot", png.string()});
  EXPECT_EQ(none.code, 1) << none.out;
  EXPECT_TRUE(none.has("no job to follow on machine 'sim1' at " + api)) << none.out;
}

// `toolpath --engine gl`: the raster's CL grid from the depth buffer (EGL,
// no X), said in the report and in the program's header; where it cannot
// serve, a clear error.
TEST(ToolpathGlEngine, TheRasterFromTheDepthBufferAndWhereItCannotServe) {
  const std::string gear = std::string(CNCSTREAM_SHARED_MESHES) + "/gearwheel.bin.stl";
  const fs::path nc = temp_dir() / "gear_gl.nc";
  const ScopedEnv no_display("DISPLAY", nullptr);
  const ScopedEnv asan("ASAN_OPTIONS", kRenderChildAsan);
  auto r = run_cncstream({"toolpath", gear, "--tool", "ball:3", "--stepover", "2", "--strategy", "raster", "--stock",
                          "none", "--engine", "gl", "--gl-tolerance", "0.1", "-o", nc.string()},
                         300);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(r.has("CL grid: the depth buffer (")) << r.out;
  EXPECT_TRUE(r.has("nodes were still below the exact surface")) << r.out;
  std::ifstream f(nc);
  std::stringstream text;
  text << f.rdbuf();
  EXPECT_NE(text.str().find("(CL grid of the rows: the depth buffer [GL engine], tessellation tolerance 0.1)\n(mm,"),
            std::string::npos);
  r = run_cncstream({"toolpath", gear, "--tool", "ball:3", "--engine", "gl", "-o", nc.string()});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.has("steep-and-shallow finishing and rest machining need the exact engine's point queries")) << r.out;
  r = run_cncstream({"toolpath", gear, "--tool", "ball:3", "--gl-tolerance", "0.1", "-o", nc.string()});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.has("--gl-tolerance applies to --engine gl only")) << r.out;
}

// `cncstream FILE sim --view`: the window beside the streaming session (on
// a private X server); without a terminal it closes when the job ends. The
// material it cut is the slot's, and for an STL job the simulator's own.
TEST(ViewBesideTheJob, TheWindowFollowsTheLocalSessionAndAgreesWithTheSimulator) {
  const PrivateXServer x;
  ASSERT_FALSE(x.display().empty()) << "Xvfb did not start (scripts/setup.sh installs xvfb)";
  const ScopedEnv display("DISPLAY", x.display().c_str());
  const ScopedEnv asan("ASAN_OPTIONS", kRenderChildAsan);
  const fs::path nc = temp_dir() / "slot_view.nc";
  std::ofstream(nc) << testparts::kSlotProgram;
  auto r = run_cncstream({nc.string(), "sim", "--yes", "--view", "--sim-speed", "max"}, 120);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(r.has("viewer: stock 601 x 401 nodes at 0.050 mm")) << r.out;
  const double slot = (10 * 6 + M_PI * 9) * 2;
  EXPECT_NEAR(number_after(r.out, "viewer: 6 of 6 segments cut into the stock, "), slot, 0.03 * slot) << r.out;

  // An STL job: the part colours the cut; the stock is the simulator's (the part's box).
  r = run_cncstream({plaque(), "sim", "--tool", "ball:3.175", "--stepover", "4", "--strategy", "raster", "--stock",
                     "none", "--yes", "--view", "--sim-speed", "max"},
                    300);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(r.has(", coloured by deviation from the part")) << r.out;
  const double viewer = number_after(r.out.substr(r.out.find("segments cut into the stock, ")),
                                     "segments cut into the stock, ");
  const auto removed = r.out.find(" mm^3 removed in ");
  ASSERT_NE(removed, std::string::npos) << r.out;
  const double sim = number_after(r.out.substr(r.out.rfind("sim: ", removed)), "sim: ");
  EXPECT_NEAR(viewer, sim, 0.02 * sim) << r.out;  // grids of 0.2 and 0.1 mm
}
