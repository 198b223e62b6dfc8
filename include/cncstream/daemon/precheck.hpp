#pragma once
// The checks every request passes before its body is read: the route exists,
// the token, Origin/Host, the client id, and for an upload its declared size.
// Api::precheck is this with the daemon's router, Auth and limits; being pure
// (no socket), it is also what the HTTP fuzz target drives.
#include <optional>
#include <string>

#include "cncstream/daemon/auth.hpp"
#include "cncstream/daemon/config.hpp"
#include "cncstream/daemon/http_types.hpp"
#include "cncstream/daemon/router.hpp"

namespace cncstream::daemon {

// POST /api/v1/files: the body is spooled to a file, not read as JSON.
bool is_upload(const Request& r);
// 1-64 letters, digits, '_' or '-'.
bool valid_client_id(const std::string& s);

// Fills r.params and r.client_id. nullopt: go on and read the body.
std::optional<Response> precheck_request(const Router& router, Auth& auth, const Limits& limits, Request& r,
                                         bool websocket_upgrade);

}  // namespace cncstream::daemon
