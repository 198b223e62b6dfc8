// The shop view over the API (docs/api-v1.md, "Shop"): GET /api/v1/shop,
// /api/v1/shop/machines, /api/v1/shop/jobs and /api/v1/shop/jobs/{id}/events.
// Read-only; the hub is read by the shop link's view reader on its own
// thread, which answers the request when PostgreSQL has: the event loop
// never waits on the hub.
#include <algorithm>

#include "cncstream/daemon/api.hpp"
#include "cncstream/daemon/body_fields.hpp"
#include "cncstream/daemon/shop_link.hpp"
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
std::string machine_query(const Request& r) {
  const auto v = r.query_value("machine");
  if (!v || v->empty()) return {};
  const bool ok = v->size() <= 32 && std::all_of(v->begin(), v->end(), [](char c) {
                    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
                  });
  if (!ok) throw ApiError{400, "bad_request", cat({"machine: '", v->substr(0, 40), "' is not a machine name (1 to 32 of A-Z a-z 0-9 _ -)"})};
  return *v;
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
    }
  });
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
                             {"poll_ms", 1000}}));
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
}

}  // namespace cncstream::daemon
