#include "cncstream/daemon/precheck.hpp"

#include <algorithm>
#include <cctype>
#include <cstdlib>

namespace cncstream::daemon {

bool is_upload(const Request& r) { return r.method == "POST" && r.path == "/api/v1/files"; }

bool valid_client_id(const std::string& s) {
  return !s.empty() && s.size() <= 64 && std::all_of(s.begin(), s.end(), [](char c) {
           return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
         });
}

std::optional<Response> precheck_request(const Router& router, Auth& auth, const Limits& limits, Request& r, bool ws) {
  int status = 0;
  const Route* route = router.match(r, status);
  if (!route) {
    if (status == 405) return Response::error(405, "method_not_allowed", r.method + " is not allowed on " + r.path);
    // Unknown paths get a 404 only after the auth check (a 404 vs 401 would map the API for strangers).
    if (auto e = auth.check(r, ws)) return e;
    return Response::error(404, "not_found", "no route " + r.path.substr(0, 200));
  }
  if (!route->public_route)
    if (auto e = auth.check(r, ws)) return e;
  r.client_id = r.header("x-client-id");
  if (ws && r.client_id.empty()) r.client_id = r.query_value("client_id").value_or("");
  if (!r.client_id.empty() && !valid_client_id(r.client_id))
    return Response::error(400, "bad_request", "X-Client-Id: use 1-64 letters, digits, '_' or '-'");
  if (is_upload(r)) {
    const std::string len = r.header("content-length");
    if (len.empty())
      return Response::error(411, "length_required", "an upload needs Content-Length (at most " +
                                                         std::to_string(limits.max_upload_bytes) + " bytes)");
    char* end = nullptr;
    const unsigned long long n = std::strtoull(len.c_str(), &end, 10);
    if (*end || n > limits.max_upload_bytes)
      return Response::error(413, "too_large", "the upload's " + len.substr(0, 24) + " bytes exceed the limit of " +
                                                   std::to_string(limits.max_upload_bytes));
  }
  return std::nullopt;
}

}  // namespace cncstream::daemon
