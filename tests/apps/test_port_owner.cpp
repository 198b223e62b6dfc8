// The CLI and port ownership without a daemon: `cncstream status` lists the
// lock files' owners, and the main command refuses a port another program
// holds, naming it, before any tool path is computed.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <cstdlib>

#include "app_run.hpp"
#include "support/pty.hpp"
#include "cncstream/transport/port_lock.hpp"

using namespace apptest;
namespace tr = cncstream::transport;

namespace {

using test_support::Pty;

// A private lock folder and an address where no daemon listens, for this
// process and the programs it runs.
class PortOwnerCli : public ::testing::Test {
 protected:
  void SetUp() override {
    static int n = 0;
    locks = temp_dir() / ("locks" + std::to_string(n++));
    fs::create_directories(locks);
    ::setenv("CNCSTREAM_LOCK_DIR", locks.c_str(), 1);
    ::setenv("CNCSTREAM_DAEMON", "http://127.0.0.1:1", 1);  // port 1: nothing listens there
    tr::set_lock_identity({"owner-test", ""});
  }
  void TearDown() override {
    ::unsetenv("CNCSTREAM_LOCK_DIR");
    ::unsetenv("CNCSTREAM_DAEMON");
    tr::set_lock_identity({});
  }
  fs::path locks;
};

}  // namespace

TEST_F(PortOwnerCli, StatusWithoutADaemonListsThePortsOwners) {
  Pty pty;
  const tr::PortLock held = tr::PortLock::acquire(pty.slave);
  ASSERT_TRUE(held.held());
  const std::string pid = std::to_string(::getpid());

  const auto r = run_cncstream({"status"});
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(r.has("no cncstream daemon is running (http://127.0.0.1:1: ")) << r.out;
  EXPECT_TRUE(r.has("serial ports in use (lock files in " + locks.string() + "):")) << r.out;
  EXPECT_TRUE(r.has(tr::resolve_device(pty.slave) + "  owner-test (pid " + pid + ") since ")) << r.out;

  const auto j = run_cncstream({"status", "--json"});
  EXPECT_EQ(j.code, 0) << j.out;
  const auto doc = nlohmann::json::parse(j.out, nullptr, false);
  ASSERT_FALSE(doc.is_discarded()) << j.out;
  EXPECT_TRUE(doc["daemon"].is_null());
  ASSERT_EQ(doc["ports"].size(), 1u) << j.out;
  EXPECT_EQ(doc["ports"][0]["device"], tr::resolve_device(pty.slave));
  EXPECT_EQ(doc["ports"][0]["pid"], ::getpid());
  EXPECT_EQ(doc["ports"][0]["program"], "owner-test");
  EXPECT_EQ(doc["ports"][0]["alive"], true);
}

TEST_F(PortOwnerCli, StatusWithNothingLockedSaysSo) {
  const auto r = run_cncstream({"status"});
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(r.has("no cncstream daemon is running")) << r.out;
  EXPECT_TRUE(r.has("no serial port is locked (lock files in " + locks.string() + ")")) << r.out;
}

TEST_F(PortOwnerCli, AHeldPortIsRefusedBeforeTheToolPathNamingItsOwner) {
  Pty pty;
  const tr::PortLock held = tr::PortLock::acquire(pty.slave);
  const auto r = run_cncstream({plaque(), pty.slave, "--tool", "ball:3.175", "--stepover", "2", "--yes"});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.has("cannot open " + pty.slave + ": it is in use by owner-test (pid " + std::to_string(::getpid()) +
                    ") since "))
      << r.out;
  EXPECT_FALSE(r.has("plan for")) << r.out;
}
