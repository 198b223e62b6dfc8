// The shop view over the API (docs/api-v1.md, "Shop"): GET /api/v1/shop,
// /api/v1/shop/machines, /api/v1/shop/jobs and /api/v1/shop/jobs/{id}/events;
// and the operator's acts from the web page: POST /api/v1/shop/jobs (submit),
// /shop/jobs/{id}/cancel and /shop/jobs/{id}/requeue, through the hub's own
// functions. The hub is reached by the shop link's view reader on its own
// thread, which answers the request when PostgreSQL has: the event loop
// never waits on the hub.
#include <algorithm>
#include <fstream>
#include <sstream>

#include "cncstream/daemon/api.hpp"
#include "cncstream/daemon/body_fields.hpp"
#include "cncstream/daemon/job_params.hpp"
#include "cncstream/daemon/shop_link.hpp"
#include "cncstream/shop/hub.hpp"
#include "cncstream/shop/pg.hpp"

namespace cncstream::daemon {

using nlohmann::json;

namespace detail_api_shop {

ApiError not_in_shop() {
  return ApiError{409, "not_in_shop",
                  "this daemon has not joined a shop ([shop] url in its configuration, or cncstreamd --shop URL)"};
}

// Comma-separated statuses, each one of the hub's.
std::vector<std::string> statuses_query(const Request& r) {
  std::vector<std::string> out;
  const auto v = r.query_value("status");
  if (!v || v->empty()) return out;
  std::size_t start = 0;
  while (start <= v->size()) {
    const auto end = std::min(v->find(',', start), v->size());
    const std::string s = v->substr(start, end - start);
    const auto& known = shop::job_statuses();
    if (std::find(known.begin(), known.end(), s) == known.end()) {
      std::string list;
      for (const auto& k : known) list.append(list.empty() ? "" : ", ").append(k);
      throw ApiError{400, "bad_request", cat({"status: '", s.substr(0, 32), "' is not a shop job's status (", list, ")"})};
    }
    out.push_back(s);
    start = end + 1;
  }
  return out;
}

// A machine's name as the hub allows it ([A-Za-z0-9_-]{1,32}).
std::string machine_name(const std::string& v) {
  const bool ok = !v.empty() && v.size() <= 32 && std::all_of(v.begin(), v.end(), [](char c) {
                    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
                  });
  if (!ok) throw ApiError{400, "bad_request", cat({"machine: '", v.substr(0, 40), "' is not a machine name (1 to 32 of A-Z a-z 0-9 _ -)"})};
  return v;
}

std::string machine_query(const Request& r) {
  const auto v = r.query_value("machine");
  if (!v || v->empty()) return {};
  return machine_name(*v);
}

// A submission's "needs": capability tags, each 1 to 64 printable characters.
std::vector<std::string> needs_field(const json& b) {
  std::vector<std::string> out;
  if (!b.contains("needs") || b["needs"].is_null()) return out;
  if (!b["needs"].is_array() || b["needs"].size() > 32)
    throw ApiError{400, "bad_request", "needs: an array of at most 32 capability tags (strings)"};
  for (const auto& t : b["needs"]) {
    const std::string tag = t.is_string() ? t.get<std::string>() : std::string();
    if (tag.empty() || tag.size() > 64 ||
        !std::all_of(tag.begin(), tag.end(), [](char c) { return c > ' ' && c != 0x7f; }))
      throw ApiError{400, "bad_request",
                     cat({"needs: '", tag.substr(0, 64), "' is not a capability tag (1 to 64 printable characters, no space)"})};
    out.push_back(tag);
  }
  return out;
}

// The hub said no: its own words, with the status that fits.
Response refused(const shop::ViewAnswer& a) {
  if (a.sqlstate == "42501")
    return Response::error(403, "hub_forbidden",
                           cat({"the hub does not let this daemon's login do that (", a.message,
                                "): its administrator grants cncstream_web_operator to this PC's login (docs/shop.md, \"Roles\")"}));
  if (a.sqlstate == "P0001") return Response::error(409, "conflict", a.message);
  return Response::error(400, "bad_request", a.message);
}

// Sends the read to the hub's reader; the answer comes from its thread.
void read_hub(ShopLink& shop, shop::ShopViewReader::Read read, const Respond& res, std::string not_found) {
  shop.view().submit(std::move(read), [res, not_found = std::move(not_found)](shop::ViewAnswer a) {
    switch (a.kind) {
      case shop::ViewAnswer::Kind::ok:
        res(Response::json(200, a.body));
        break;
      case shop::ViewAnswer::Kind::not_found:
        res(Response::error(404, "not_found", not_found));
        break;
      case shop::ViewAnswer::Kind::hub_unavailable:
        res(Response::error(503, "hub_unavailable", a.message));
        break;
      case shop::ViewAnswer::Kind::refused:
        res(refused(a));
        break;
    }
  });
}

// Reads the stored file for the hub (on the reader's thread: it may be large).
std::string file_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  if (!in && !in.eof()) throw shop::ShopError(p.string() + ": cannot read the file to submit");
  return s.str();
}

}  // namespace detail_api_shop

void Api::shop_routes() {
  using namespace detail_api_shop;
  // Whether this daemon is in a shop (the page shows its Shop view then), and how its link is.
  router_.add("GET", "/api/v1/shop", [this](Request&, const Respond& res) {
    if (!shop_) {
      res(Response::json(200, {{"member", false}}));
      return;
    }
    auto& c = shop_->client();
    res(Response::json(200, {{"member", true},
                             {"name", c.settings().name},
                             {"pc", c.settings().pc},
                             {"hub", shop::redact_url(c.settings().url)},
                             {"hub_up", c.hub_up()},
                             {"unsent_events", c.unsent()},
                             {"poll_ms", 5000}}));  // a slow fallback: the `shop` frame brings changes at once
  });
  router_.add("GET", "/api/v1/shop/machines", [this](Request&, const Respond& res) {
    if (!shop_) throw not_in_shop();
    read_hub(*shop_, [](shop::PgConnection& db) -> std::optional<json> { return shop::view_machines(db); }, res, "");
  });
  router_.add("GET", "/api/v1/shop/jobs", [this](Request& r, const Respond& res) {
    if (!shop_) throw not_in_shop();
    shop::JobFilter f;
    f.statuses = statuses_query(r);
    f.machine = machine_query(r);
    f.limit = static_cast<int>(bounded_query(r, "limit", 100, 1, 500));
    f.before = bounded_query(r, "before", 0, 0, 999'999'999'999LL);
    read_hub(*shop_, [f](shop::PgConnection& db) -> std::optional<json> { return shop::view_jobs(db, f); }, res, "");
  });
  router_.add("GET", "/api/v1/shop/jobs/{id}/events", [this](Request& r, const Respond& res) {
    if (!shop_) throw not_in_shop();
    const std::int64_t id = job_id_param(r.params.at(0));
    const int limit = static_cast<int>(bounded_query(r, "limit", 1000, 1, 5000));
    read_hub(*shop_, [id, limit](shop::PgConnection& db) { return shop::view_job_events(db, id, limit); }, res,
             cat({"the shop has no job ", std::to_string(id)}));
  });
  shop_act_routes();
}

// The operator's acts from the web page, as `cncstream submit` and
// `cncstream shop requeue` do them: the hub's functions, under this
// daemon's login (which needs cncstream_web_operator for them).
void Api::shop_act_routes() {
  using namespace detail_api_shop;
  // Submits a file of this daemon's store (uploaded with POST /files) to the shop's queue.
  router_.add("POST", "/api/v1/shop/jobs", [this](Request& r, const Respond& res) {
    if (!shop_) throw not_in_shop();
    const json b = parse_body(r);
    if (!b.contains("file") || !b["file"].is_string())
      throw ApiError{400, "bad_request", "file: required, the id of an uploaded file (POST /api/v1/files)"};
    const std::string file = b["file"].get<std::string>();
    const auto info = is_file_id(file) ? files_.get(file) : std::nullopt;
    const auto path = info ? files_.content_path(file) : std::nullopt;
    if (!info || !path) throw ApiError{404, "not_found", cat({"file: no uploaded file ", file.substr(0, 64)})};
    shop::Submission s;
    s.file_name = info->name;
    s.kind = info->kind;
    s.needs = needs_field(b);
    if (b.contains("machine") && !b["machine"].is_null()) {
      if (!b["machine"].is_string()) throw ApiError{400, "bad_request", "machine: a machine's name, or null for any that can"};
      s.machine = machine_name(b["machine"].get<std::string>());
    }
    const bool has_params = b.contains("params") && !b["params"].is_null();
    if (info->kind == "stl") {
      // Checked here as the claiming daemon will (a tool's spec, not this PC's tool numbers).
      if (!has_params || !b["params"].is_object() || !b["params"].contains("tool"))
        throw ApiError{400, "bad_request", "params: an STL needs its tool path parameters, with \"tool\" (e.g. \"ball:3.175\")"};
      if (b["params"]["tool"].is_number())
        throw ApiError{400, "bad_request", "params.tool: a cutter's spec (e.g. \"ball:3.175\"): a tool number is this PC's, not the shop's"};
      check_toolpath_params(b["params"], *info, config_.limits);
      s.params_json = b["params"].dump();
    } else if (has_params) {
      throw ApiError{400, "bad_request", "params: only for an STL; a program runs as it is"};
    }
    read_hub(*shop_, [s = std::move(s), p = *path](shop::PgConnection& db) mutable -> std::optional<json> {
      s.content = file_bytes(p);
      const auto id = shop::Hub(db).submit_job(s);
      return json{{"id", id}, {"status", "pending"}, {"file_name", s.file_name}, {"kind", s.kind}};
    }, [res](Response resp) {
      if (resp.status == 200) resp.status = 201;
      res(std::move(resp));
    }, "");
  });
  // A job that has not started: cancelled on the hub (the machine holding it drops it).
  router_.add("POST", "/api/v1/shop/jobs/{id}/cancel", [this](Request& r, const Respond& res) {
    if (!shop_) throw not_in_shop();
    const std::int64_t id = job_id_param(r.params.at(0));
    read_hub(*shop_, [id](shop::PgConnection& db) -> std::optional<json> {
      shop::Hub(db).cancel_job(id);
      return json{{"id", id}, {"status", "cancelled"}};
    }, res, "");
  });
  // An interrupted, failed or cancelled job back in the queue: only when the
  // operator says where ("on": the machine it ran on, to resume there, or any).
  router_.add("POST", "/api/v1/shop/jobs/{id}/requeue", [this](Request& r, const Respond& res) {
    if (!shop_) throw not_in_shop();
    const std::int64_t id = job_id_param(r.params.at(0));
    const json b = parse_body(r);
    const std::string on = b.contains("on") && b["on"].is_string() ? b["on"].get<std::string>() : "";
    if (on != "same_machine" && on != "any_machine")
      throw ApiError{400, "bad_request",
                     "on: required, \"same_machine\" (back to the machine it ran on) or \"any_machine\" (any that can)"};
    read_hub(*shop_, [id, same = on == "same_machine", on](shop::PgConnection& db) -> std::optional<json> {
      shop::Hub(db).requeue_job(id, same);
      return json{{"id", id}, {"status", "pending"}, {"on", on}};
    }, res, "");
  });
}

}  // namespace cncstream::daemon
