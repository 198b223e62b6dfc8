#pragma once
// `cncstream FILE PORT` when a running daemon owns PORT: the port cannot be
// opened (one owner per port), so the job goes to the daemon through its API
// (upload, create, plan, confirm, start) and is followed here with the same
// live panel, keys and exit codes as a local run.
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "cncstream/transport/port_lock.hpp"
#include "daemon_client.hpp"
#include "job_session.hpp"
#include "toolpath_options.hpp"

namespace cncstream::app {

struct DaemonOwner {
  transport::PortOwner owner;  // from the port's lock file
  DaemonAddress address;       // its API, which answered
};

// Who owns `port` when that decides the run: nullopt when nobody does (or the
// port is `sim`/`auto`), a DaemonOwner when a daemon whose API answers does.
// Throws std::runtime_error with the lock's message when another program owns
// it, or when the owning daemon's API does not answer (no tool path is
// generated for a port that cannot be had).
std::optional<DaemonOwner> daemon_owning_port(const std::string& port);

// The API's job parameters for the CLI's tool path options (the daemon takes
// mm or in: a part in metres is sent as mm with the scale times 1000).
nlohmann::json job_params_from(const ToolpathOptions& tp);

struct HandoffJob {
  std::string file;
  bool stl = false;
  ToolpathOptions tp;  // STL only
  std::string output;  // STL only: write the daemon's program here too
};

// Runs the job on the daemon and returns the process's exit code: 0 done,
// 1 not completed (stopped, failed, interrupted, refused), 2 not started
// (the operator said no).
int hand_off_to_daemon(const DaemonOwner& daemon, const HandoffJob& job, const ConnectionOptions& c);

}  // namespace cncstream::app
