// Routines outside a job (corner probing) through the machine session,
// against the built-in simulator with a block and a corner plate: the session
// runs it line by line, refuses other motion meanwhile, and a lost link ends
// it with nothing written.
#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>

#include "cncstream/protocol/corner_probe.hpp"
#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/session/machine_session.hpp"
#include "cncstream/session/simulator_port.hpp"
#include "support/run_until.hpp"

using namespace cncstream;
using namespace cncstream::session;
using cncstream::test::run_until;

namespace {

// A block X 20..120, Y 20..100, its top at Z -30 (machine); a 5 mm corner
// plate with 3 mm lips on its X/Y-min corner; a 6 mm flat end mill 10 mm
// above the plate.
struct CornerRig {
  boost::asio::io_context io;
  std::shared_ptr<SimulatorPort> sim;
  std::unique_ptr<MachineSession> session;
  Subscription watch;
  std::vector<std::string> prompts;
  std::optional<bool> ended_ok;
  std::string end_text;
  bool confirm = true;

  explicit CornerRig(std::size_t vanish_after = 0) {
    SimulatorOptions so;
    so.stock = geometry::Box3{geometry::Vec3{20, 20, -50}, geometry::Vec3{120, 100, -30}};
    so.cutter = cam::parse_cutter_spec("flat:6");
    so.corner_plate = "5,3";
    so.start_position = geometry::Vec3{42, 42, -15};
    so.faults.vanish_after = vanish_after;
    sim = std::make_shared<SimulatorPort>(so);
    MachineOptions o;
    o.name = "corner";
    o.port = sim;
    o.profiles_dir = protocol::default_profiles_dir();
    session = std::make_unique<MachineSession>(io, o);
    watch = session->subscribe([this](const SessionEvent& e) {
      if (e.kind != SessionEventKind::Routine) return;
      if (e.routine_prompt) {
        prompts.push_back(e.routine_prompt->text);
        boost::asio::post(io, [this] { confirm ? session->routine_confirm() : session->routine_decline(); });
      } else if (e.routine_succeeded) {
        ended_ok = *e.routine_succeeded;
        end_text = e.text;
      }
    });
    session->open();
    EXPECT_TRUE(run_until(io, [&] { return session->ready(); }));
  }
};

protocol::CornerProbeConfig rig_config() {
  protocol::CornerProbeConfig c;
  c.plate = {5, 3, 50};
  c.tool_radius = 3;
  return c;
}

}  // namespace

TEST(RoutinesOnSim, CornerProbeThroughTheSessionFindsTheBlocksCorner) {
  CornerRig rig;
  auto routine = std::make_shared<protocol::CornerProbeRoutine>(rig_config());
  ASSERT_TRUE(rig.session->run_routine(routine));
  EXPECT_TRUE(rig.session->routine_active());
  // Nothing else moves the machine meanwhile.
  EXPECT_FALSE(rig.session->jog_step({1, 0, 0}, 1, 100));
  EXPECT_FALSE(rig.session->console("G0 X0"));
  EXPECT_FALSE(rig.session->run_routine(std::make_shared<protocol::CornerProbeRoutine>(rig_config())));
  JobInput job;
  job.file = "x.nc";
  job.lines = {"G0 X1"};
  job.total_lines = 1;
  EXPECT_FALSE(rig.session->start_job(job));
  ASSERT_TRUE(run_until(rig.io, [&] { return rig.ended_ok.has_value(); }, 120));
  ASSERT_TRUE(*rig.ended_ok) << rig.end_text;
  const auto& r = routine->result();
  ASSERT_TRUE(r.edge_x && r.edge_y && r.top_z);
  EXPECT_NEAR(*r.edge_x, 20, 0.01);
  EXPECT_NEAR(*r.edge_y, 20, 0.01);
  EXPECT_NEAR(*r.top_z, -30, 0.01);
  EXPECT_TRUE(r.applied);
  EXPECT_EQ(rig.prompts.size(), 1u);
  EXPECT_FALSE(rig.session->routine_active());
  // The machine is the operator's again: work zero is on the corner.
  ASSERT_TRUE(rig.session->console("G0 X0 Y0"));
  ASSERT_TRUE(run_until(rig.io, [&] {
    const auto st = rig.session->status();
    return st && st->state == protocol::MachineState::Idle && st->wpos && std::fabs((*st->wpos)[0]) < 1e-3 &&
           std::fabs((*st->wpos)[1]) < 1e-3;
  }));
  const auto st = rig.session->status();
  ASSERT_TRUE(st && st->mpos);
  EXPECT_NEAR((*st->mpos)[0], 20, 0.01);
  EXPECT_NEAR((*st->mpos)[1], 20, 0.01);
}

TEST(RoutinesOnSim, ALostLinkMidProbeEndsItWithNothingWritten) {
  // $I and $$ are answered, then $G, $#, G21, the fast Z probe: gone.
  CornerRig rig(6);
  auto routine = std::make_shared<protocol::CornerProbeRoutine>(rig_config());
  ASSERT_TRUE(rig.session->run_routine(routine));
  ASSERT_TRUE(run_until(rig.io, [&] { return rig.ended_ok.has_value(); }, 120));
  EXPECT_FALSE(*rig.ended_ok);
  EXPECT_NE(rig.end_text.find("disconnect"), std::string::npos) << rig.end_text;
  EXPECT_FALSE(routine->result().applied);
  EXPECT_TRUE(rig.prompts.empty());
}
