// Jobs: create, list, get, the program, its preview (height PNG, thinned
// path), start, generate, hold, resume, stop, cancel, move, resume-plan and
// resume-confirm.
#include "cncstream/daemon/api.hpp"
#include "cncstream/daemon/body_fields.hpp"

namespace cncstream::daemon {

using nlohmann::json;

void Api::job_routes() {
  router_.add("POST", "/api/v1/jobs", [this](Request& r, const Respond& res) {
    res(Response::json(201, jobs_.create(parse_body(r))));
  });
  router_.add("GET", "/api/v1/jobs", [this](Request& r, const Respond& res) {
    res(Response::json(200, jobs_.list(r.query_value("machine"), r.query_value("state"))));
  });
  router_.add("GET", "/api/v1/jobs/{id}", [this](Request& r, const Respond& res) {
    res(Response::json(200, jobs_.to_json(jobs_.get(job_id(r)))));
  });
  router_.add("GET", "/api/v1/jobs/{id}/gcode", [this](Request& r, const Respond& res) {
    auto& j = jobs_.get(job_id(r));
    const auto p = jobs_.program(j);
    if (!p) throw ApiError{409, "bad_state", "job " + std::to_string(j.row.id) + " has no program yet (" + j.row.state + ")"};
    Response resp;
    resp.content_type = "text/plain; charset=us-ascii";
    resp.file = p->path;
    res(std::move(resp));
  });
  router_.add("GET", "/api/v1/jobs/{id}/clmap.png", [this](Request& r, Respond res) {
    const auto id = job_id(r);
    jobs_.get(id);  // 404 first
    const auto max = bounded_query(r, "max", Previews::kMaxPixels, Previews::kMinPixels, Previews::kMaxPixels);
    jobs_.preview_png(id, static_cast<int>(max), std::move(res));
  });
  router_.add("GET", "/api/v1/jobs/{id}/path", [this](Request& r, Respond res) {
    const auto id = job_id(r);
    jobs_.get(id);
    const auto n = bounded_query(r, "max_points", Previews::kDefaultPoints, Previews::kMinPoints, Previews::kMaxPoints);
    jobs_.preview_path(id, static_cast<std::size_t>(n), std::move(res));
  });
  router_.add("POST", "/api/v1/jobs/{id}/start", [this](Request& r, const Respond& res) {
    res(Response::json(202, jobs_.start(job_id(r), r.client_id)));
  });
  router_.add("POST", "/api/v1/jobs/{id}/generate", [this](Request& r, const Respond& res) {
    res(Response::json(202, jobs_.generate(job_id(r))));
  });
  router_.add("POST", "/api/v1/jobs/{id}/hold", [this](Request& r, const Respond& res) {
    jobs_.hold(job_id(r));
    res(Response::json(202, {{"accepted", true}}));
  });
  router_.add("POST", "/api/v1/jobs/{id}/resume", [this](Request& r, const Respond& res) {
    jobs_.resume(job_id(r), r.client_id);
    res(Response::json(202, {{"accepted", true}}));
  });
  router_.add("POST", "/api/v1/jobs/{id}/stop", [this](Request& r, const Respond& res) {
    jobs_.stop(job_id(r));
    res(Response::json(202, {{"accepted", true}}));
  });
  router_.add("POST", "/api/v1/jobs/{id}/cancel", [this](Request& r, const Respond& res) {
    res(Response::json(200, jobs_.cancel(job_id(r), r.client_id)));
  });
  router_.add("POST", "/api/v1/jobs/{id}/move", [this](Request& r, const Respond& res) {
    const json b = parse_body(r);
    if (!b.contains("position") || !b["position"].is_number_integer())
      throw ApiError{400, "bad_request", "position: required, an integer"};
    res(Response::json(200, jobs_.move(job_id(r), b["position"].get<std::int64_t>())));
  });
  router_.add("POST", "/api/v1/jobs/{id}/resume-plan", [this](Request& r, const Respond& res) {
    const json b = parse_body(r);
    long from = -1;
    if (b.contains("from_line") && !b["from_line"].is_null()) {
      if (!b["from_line"].is_number_integer()) throw ApiError{400, "bad_request", "from_line: an integer (-1: chosen from the last status)"};
      const auto v = b["from_line"].get<std::int64_t>();
      if (v < -1 || v > 100'000'000) throw ApiError{400, "bad_request", "from_line: out of range"};
      from = static_cast<long>(v);
    }
    jobs_.resume_plan(job_id(r), from, r.client_id, res);
  });
  router_.add("POST", "/api/v1/jobs/{id}/resume-confirm", [this](Request& r, const Respond& res) {
    const json b = parse_body(r);
    if (!b.contains("plan_id") || !b["plan_id"].is_string()) throw ApiError{400, "bad_request", "plan_id: required"};
    res(Response::json(201, jobs_.resume_confirm(job_id(r), b["plan_id"].get<std::string>(), r.client_id)));
  });
}

}  // namespace cncstream::daemon
