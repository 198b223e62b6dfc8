#pragma once
// Runs one routine outside a job (corner probing, the outline, a tool routine) on one
// machine session: open the port (or the simulator), wait until the
// controller is ready, run it, put its prompts to the operator (or answer
// yes with --yes), and close. The CLI's probe and outline commands share it.
#include <memory>
#include <optional>

#include "cncstream/protocol/grbl_settings.hpp"

#include "cncstream/protocol/machine_routine.hpp"
#include "cncstream/session/simulator_port.hpp"
#include "job_session.hpp"

namespace cncstream::app {

// Opens a session on a real controller (PORT, not `sim`), waits until it is
// ready (identified, `$$` read) and closes: its settings, for what must be
// known before a program is made (feeds within $30/$110). Empty when the
// controller gave none (the session's warning says why); nullopt, said on
// stderr, when the port does not open or the controller never became ready.
std::optional<protocol::GrblSettings> read_controller_settings(const ConnectionOptions& conn);

// 0: the routine succeeded; 1: it failed or was refused (said on stderr);
// 2: no port.
int run_machine_routine(const ConnectionOptions& conn, const session::SimulatorOptions& sim,
                        const std::shared_ptr<protocol::MachineRoutine>& routine);

}  // namespace cncstream::app
