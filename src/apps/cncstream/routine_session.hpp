#pragma once
// Runs one routine outside a job (corner probing, the outline, a tool routine) on one
// machine session: open the port (or the simulator), wait until the
// controller is ready, run it, put its prompts to the operator (or answer
// yes with --yes), and close. The CLI's probe and outline commands share it.
#include <memory>

#include "cncstream/protocol/machine_routine.hpp"
#include "cncstream/session/simulator_port.hpp"
#include "job_session.hpp"

namespace cncstream::app {

// 0: the routine succeeded; 1: it failed or was refused (said on stderr);
// 2: no port.
int run_machine_routine(const ConnectionOptions& conn, const session::SimulatorOptions& sim,
                        const std::shared_ptr<protocol::MachineRoutine>& routine);

}  // namespace cncstream::app
