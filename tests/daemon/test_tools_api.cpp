// The daemon's tool library: job params naming library tools and a
// material, and the /api/v1/tools routes (saved to <data_dir>/tools.toml and
// read back by a restarted daemon).
#include <gtest/gtest.h>

#include <fstream>

#include "cncstream/daemon/http_types.hpp"
#include "cncstream/daemon/job_params.hpp"
#include "daemon_test_util.hpp"

using namespace dtest;
using namespace cncstream::daemon;

namespace {

cncstream::tooling::ToolLibrary library() {
  cncstream::tooling::ToolLibrary lib;
  cncstream::tooling::Tool t;
  t.number = 4;
  t.name = "1/8 ball";
  t.geometry = cncstream::tooling::parse_tool_spec("ball:3.175");
  t.flutes = 2;
  lib.put(t, false);
  t.number = 6;
  t.name = "6 mm upcut";
  t.geometry = cncstream::tooling::parse_tool_spec("flat:6");
  t.flutes = 3;
  lib.put(t, false);
  return lib;
}

}  // namespace

TEST(JobParams, LibraryToolsAndAMaterialBecomeSpecsAndFeeds) {
  FileInfo f;
  f.kind = "stl";
  f.bbox = {0, 0, 0, 20, 20, 5};
  Limits l;
  const auto lib = library();
  cncstream::tooling::MachineLimits machine;
  machine.max_feed_xy = 3000;
  const auto c = check_toolpath_params({{"tool", "1/8 ball"}, {"rough", "6"}, {"stepover", 1}, {"material", "walnut"}},
                                       f, l, &lib, machine);
  EXPECT_EQ(c.canonical["tool"], "ball:3.175");
  EXPECT_EQ(c.canonical["rough"], "flat:6");
  EXPECT_EQ(c.canonical["material_used"], "walnut");
  // Finishing: 0.3 mm (the leave) deep, 1 mm of it wide: the spindle's 24000 rpm binds; the feed stays within $110.
  EXPECT_EQ(c.params.rpm, 24000);
  EXPECT_LT(c.params.feed, 3000);
  ASSERT_TRUE(c.params.rough_feed);
  EXPECT_EQ(*c.params.rough_feed, 3000);  // 3 flutes of a 6 mm flat want more: $110/$111 binds,
  ASSERT_TRUE(c.params.rough_rpm);         // and its rpm comes down from 23873 with the feed
  EXPECT_LT(*c.params.rough_rpm, 23873);
  // The canonical params check again to the same job without the library (the run-time check).
  const auto again = check_toolpath_params(c.canonical, f, l);
  EXPECT_EQ(again.params.feed, c.params.feed);
  EXPECT_EQ(again.params.rpm, c.params.rpm);
  EXPECT_EQ(again.params.rough_feed, c.params.rough_feed);
  EXPECT_EQ(again.params.rough_rpm, c.params.rough_rpm);
  EXPECT_EQ(again.canonical.dump(), c.canonical.dump());
  // The library's numbers go with the specs (the program's T words), through the run-time check too.
  EXPECT_EQ(c.canonical["tool_number"], 4);
  EXPECT_EQ(c.canonical["rough_tool_number"], 6);
  EXPECT_TRUE(c.canonical["rest_tool_number"].is_null());
  EXPECT_EQ(again.params.tool_number, std::optional<int>(4));
  EXPECT_EQ(again.params.rough_tool_number, std::optional<int>(6));
  // A spec has none, unless the request gives one (1-9999).
  EXPECT_FALSE(check_toolpath_params({{"tool", "ball:3"}}, f, l, &lib).params.tool_number);
  EXPECT_EQ(check_toolpath_params({{"tool", "ball:3"}, {"tool_number", 12}}, f, l).params.tool_number,
            std::optional<int>(12));
  // The operator's feed wins; an unknown tool or material names the field and the candidates.
  const auto given = check_toolpath_params({{"tool", "4"}, {"feed", 700}, {"material", "mdf"}}, f, l, &lib);
  EXPECT_EQ(given.params.feed, 700);
  auto err = [&](const json& p) -> std::string {
    try {
      check_toolpath_params(p, f, l, &lib);
    } catch (const ApiError& e) {
      return e.message;
    }
    return "";
  };
  EXPECT_NE(err({{"tool", "drill"}}).find("params.tool: no tool named 'drill'"), std::string::npos) << err({{"tool", "drill"}});
  EXPECT_NE(err({{"tool", "drill"}}).find("T4 '1/8 ball'"), std::string::npos);
  EXPECT_NE(err({{"tool", "4"}, {"material", "cheese"}}).find("params.material: unknown material 'cheese'"),
            std::string::npos);
  EXPECT_NE(err({{"tool", "4"}, {"rest", "9"}}).find("params.rest: no tool number 9"), std::string::npos);
  EXPECT_NE(err({{"tool", "ball:3"}, {"tool_number", 0}}).find("params.tool_number: expected a tool number from 1 to 9999"),
            std::string::npos);
}

TEST(DaemonTools, CreateReplaceDeleteImportAndKeepAcrossARestart) {
  const auto dir = temp_dir("tools");
  auto cfg = test_config(dir);
  cfg.machines = {sim_machine("sim1")};
  {
    RunningDaemon d(cfg);
    const Http& h = d.http;
    auto r = h.post("/api/v1/tools", {{"name", "1/8 tapered ball"}, {"shape", "taper:1:5:3.175"}, {"stick_out", 30}});
    ASSERT_EQ(r.status, 201) << r.body;
    EXPECT_EQ(r.j()["number"], 1);
    EXPECT_EQ(r.j()["description"], "1 mm tapered ball-nose, 5° per side, 3.175 mm at the top");
    r = h.post("/api/v1/tools", {{"number", 1}, {"name", "x"}, {"shape", "flat:6"}});
    EXPECT_EQ(r.status, 409) << r.body;
    r = h.post("/api/v1/tools", {{"name", "bad"}, {"shape", "vbit:200:6"}});
    EXPECT_EQ(r.status, 400);
    EXPECT_NE(r.body.find("included angle 200"), std::string::npos) << r.body;
    r = h.request("PUT", "/api/v1/tools/1",
                  json({{"name", "1/8 tapered ball"}, {"shape", "taper:1:5:3.175"}, {"flutes", 2}, {"stick_out", 32},
                        {"cutting", {{{"material", "walnut"}, {"rpm", 18000}, {"chip_load", 0.03}}}}})
                      .dump(),
                  {{"Content-Type", "application/json"}});
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_EQ(h.get("/api/v1/tools/1").j()["stick_out"], 32);
    r = h.post("/api/v1/tools/import", {{"name", "tool.tbl"}, {"content", "T5 P5 Z40 D3.175 ;1/8 ball nose\nT6 Z2\n"}});
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_EQ(r.j()["understood"].size(), 1u);
    EXPECT_EQ(r.j()["skipped"].size(), 1u);
    r = h.post("/api/v1/tools/import", {{"name", "tool.tbl"}, {"content", "T5 D?\n"}});
    EXPECT_EQ(r.status, 400);
    EXPECT_NE(r.body.find("\"tool.tbl:1: 'D?' at column 4"), std::string::npos) << r.body;  // its name, not a temporary file's
    EXPECT_EQ(h.get("/api/v1/tools").j()["tools"].size(), 2u);
    EXPECT_EQ(h.request("DELETE", "/api/v1/tools/5", "", {}).status, 200);
    EXPECT_EQ(h.request("DELETE", "/api/v1/tools/5", "", {}).status, 404);
    EXPECT_EQ(h.get("/api/v1/tools/77").status, 404);
  }
  // Saved: a new daemon on the same data folder has the tool, with its data.
  {
    RunningDaemon d(cfg);
    const json tools = d.http.get("/api/v1/tools").j()["tools"];
    ASSERT_EQ(tools.size(), 1u);
    EXPECT_EQ(tools[0]["cutting"][0]["material"], "walnut");
  }
  std::ifstream in(cfg.data_dir / "tools.toml");
  EXPECT_TRUE(in.good());
}
