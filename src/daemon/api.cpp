#include "cncstream/daemon/api.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>

namespace cncstream::daemon {

using nlohmann::json;

namespace {

bool valid_client_id(const std::string& s) {
  return !s.empty() && s.size() <= 64 &&
         std::all_of(s.begin(), s.end(), [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-'; });
}

}  // namespace

json parse_body(const Request& r) {
  if (r.body.empty()) return json::object();
  try {
    return json::parse(r.body);
  } catch (const json::parse_error& e) {
    throw ApiError{400, "bad_request", "malformed JSON at byte " + std::to_string(e.byte) + " of the body"};
  }
}

Api::Api(boost::asio::io_context& io, boost::asio::thread_pool& pool, const DaemonConfig& config, Auth& auth,
         FileStore& files, Machines& machines, JobManager& jobs, WsHub& hub, std::filesystem::path web_root)
    : io_(io),
      pool_(pool),
      config_(config),
      auth_(auth),
      files_(files),
      machines_(machines),
      jobs_(jobs),
      hub_(hub),
      web_root_(std::move(web_root)) {
  add_routes();
}

Machine& Api::machine(const Request& r, std::size_t param) {
  Machine* m = param < r.params.size() ? machines_.find(r.params[param]) : nullptr;
  if (!m) throw ApiError{404, "not_found", "no machine '" + (param < r.params.size() ? r.params[param].substr(0, 64) : "") + "'"};
  return *m;
}

std::int64_t Api::job_id(const Request& r) const {
  const std::string& s = r.params.at(0);
  if (s.empty() || s.size() > 18 || !std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; }))
    throw ApiError{404, "not_found", "no job '" + s.substr(0, 64) + "'"};
  return std::stoll(s);
}

std::optional<Response> Api::precheck(Request& r, bool ws) {
  int status = 0;
  const Route* route = router_.match(r, status);
  if (!route) {
    if (status == 405) return Response::error(405, "method_not_allowed", r.method + " is not allowed on " + r.path);
    // Unknown paths get a 404 only after the auth check (a 404 vs 401 would map the API for strangers).
    if (auto e = auth_.check(r, ws)) return e;
    return Response::error(404, "not_found", "no route " + r.path.substr(0, 200));
  }
  if (!route->public_route)
    if (auto e = auth_.check(r, ws)) return e;
  r.client_id = r.header("x-client-id");
  if (ws && r.client_id.empty()) r.client_id = r.query_value("client_id").value_or("");
  if (!r.client_id.empty() && !valid_client_id(r.client_id))
    return Response::error(400, "bad_request", "X-Client-Id: use 1-64 letters, digits, '_' or '-'");
  if (is_upload(r)) {
    const std::string len = r.header("content-length");
    if (len.empty())
      return Response::error(411, "length_required", "an upload needs Content-Length (at most " +
                                                         std::to_string(config_.limits.max_upload_bytes) + " bytes)");
    char* end = nullptr;
    const unsigned long long n = std::strtoull(len.c_str(), &end, 10);
    if (*end || n > config_.limits.max_upload_bytes)
      return Response::error(413, "too_large", "the upload's " + len.substr(0, 24) + " bytes exceed the limit of " +
                                                   std::to_string(config_.limits.max_upload_bytes));
  }
  return std::nullopt;
}

void Api::handle(Request r, Respond respond) {
  int status = 0;
  const Route* route = router_.match(r, status);
  if (!route) {
    respond(Response::error(status, status == 405 ? "method_not_allowed" : "not_found", "no route " + r.path.substr(0, 200)));
    return;
  }
  machines_.touch(r.client_id);
  try {
    route->handler(r, respond);
  } catch (const ApiError& e) {
    respond(Response::error(e.status, e.code, e.message));
  } catch (const json::exception& e) {
    respond(Response::error(400, "bad_request", std::string("bad JSON value: ") + e.what()));
  } catch (const std::exception& e) {
    spdlog::error("{} {}: {}", r.method, r.path, e.what());
    respond(Response::error(500, "internal", e.what()));
  }
}

void Api::add_routes() {
  router_.add("GET", "/api/v1/health", [](Request&, Respond res) {
    res(Response::json(200, {{"ok", true}, {"version", "0.1.0"}}));
  }, true);
  router_.add("GET", "/api/v1/openapi.json", [](Request&, Respond res) {
    Response r;
    r.body = openapi_json();
    res(std::move(r));
  });
  router_.add("POST", "/api/v1/ws-token", [this](Request&, Respond res) {
    res(Response::json(200, {{"token", auth_.issue_ws_token()}, {"expires_in_s", 30}}));
  });
  // The upgrade itself is taken by the server; a plain GET gets told so.
  router_.add("GET", "/api/v1/ws", [](Request&, Respond res) {
    res(Response::error(400, "bad_request", "/api/v1/ws is a WebSocket: send an Upgrade request"));
  });
  machine_routes();
  file_routes();
  job_routes();
  static_routes();
}

// ---- WebSocket --------------------------------------------------------------

std::shared_ptr<WsClient> Api::ws_open(const Request& upgrade, std::weak_ptr<WsPeer> peer) {
  auto c = hub_.add(upgrade.client_id, std::move(peer));
  if (!c) return nullptr;
  hub_.send(*c, WsHub::frame(json{{"type", "hello"}, {"client_id", upgrade.client_id}, {"machines", machines_.names()},
                                  {"version", "0.1.0"}}.dump()));
  return c;
}

void Api::ws_close(WsClient& c) {
  const std::string cid = c.client_id;
  const auto id = c.id;
  hub_.remove(id);
  machines_.client_gone(cid, id);
}

void Api::ws_message(WsClient& c, const std::string& text) {
  json msg;
  json id = nullptr;
  auto reply_error = [&](const std::string& code, const std::string& message) {
    hub_.send(c, WsHub::frame(json{{"type", "error"}, {"id", id}, {"code", code}, {"message", message}}.dump()));
  };
  try {
    msg = json::parse(text);
  } catch (const json::parse_error& e) {
    reply_error("bad_request", "malformed JSON at byte " + std::to_string(e.byte));
    return;
  }
  if (!msg.is_object() || !msg.contains("type") || !msg["type"].is_string()) {
    reply_error("bad_request", "expected an object with a string 'type'");
    return;
  }
  if (msg.contains("id")) id = msg["id"];
  machines_.touch(c.client_id);
  const std::string type = msg["type"].get<std::string>();
  auto ack = [&] { hub_.send(c, WsHub::frame(json{{"type", "ack"}, {"id", id}}.dump())); };
  try {
    if (type == "ping") {
      hub_.send(c, WsHub::frame(json{{"type", "pong"}, {"id", id}}.dump()));
      return;
    }
    if (type == "subscribe") {
      if (!msg.contains("machines") || !msg["machines"].is_array()) throw ApiError{400, "bad_request", "machines: expected an array"};
      std::set<std::string> set;
      bool all = false;
      for (const auto& m : msg["machines"]) {
        if (!m.is_string()) throw ApiError{400, "bad_request", "machines: expected names"};
        const auto n = m.get<std::string>();
        if (n == "*") all = true;
        else if (!machines_.find(n)) throw ApiError{404, "not_found", "no machine '" + n.substr(0, 64) + "'"};
        else set.insert(n);
      }
      c.machines = std::move(set);
      c.all_machines = all;
      ack();
      // A fresh subscriber sees each machine's state at once, not at the next report.
      for (const auto& m : machines_.all())
        if (c.wants(m->config.name)) c.queue.push_status(m->config.name, WsHub::frame(machines_.status_frame(*m)));
      if (auto p = c.peer.lock()) p->kick();
      return;
    }
    if (type == "jog_start" || type == "jog_renew" || type == "jog_release") {
      if (!msg.contains("machine") || !msg["machine"].is_string()) throw ApiError{400, "bad_request", "machine: required"};
      Machine* m = machines_.find(msg["machine"].get<std::string>());
      if (!m) throw ApiError{404, "not_found", "no machine '" + msg["machine"].get<std::string>().substr(0, 64) + "'"};
      auto& s = *m->session;
      if (type == "jog_release") {
        s.jog_release();  // never refused: stopping is always allowed
        if (m->jog_ws_client == c.id) m->jog_ws_client = 0;
        ack();
        return;
      }
      if (type == "jog_renew") {
        if (m->jog_ws_client != c.id) throw ApiError{409, "bad_state", "no jog of yours runs on " + m->config.name};
        if (auto r = s.jog_renew(); !r) {
          m->jog_ws_client = 0;
          throw ApiError{409, "refused", r.reason};
        }
        ack();
        return;
      }
      machines_.require_control(*m, c.client_id);
      if (!msg.contains("dir") || !msg["dir"].is_array() || msg["dir"].size() != 3)
        throw ApiError{400, "bad_request", "dir: expected [x, y, z]"};
      protocol::JogDirection dir;
      double norm = 0;
      for (int i = 0; i < 3; ++i) {
        if (!msg["dir"][i].is_number()) throw ApiError{400, "bad_request", "dir: expected 3 numbers"};
        dir.v[static_cast<std::size_t>(i)] = msg["dir"][i].get<double>();
        if (!std::isfinite(dir.v[static_cast<std::size_t>(i)])) throw ApiError{400, "bad_request", "dir: not finite"};
        norm += std::abs(dir.v[static_cast<std::size_t>(i)]);
      }
      if (norm == 0) throw ApiError{400, "bad_request", "dir: all zero"};
      if (!msg.contains("feed") || !msg["feed"].is_number()) throw ApiError{400, "bad_request", "feed: required, mm/min"};
      const double feed = msg["feed"].get<double>();
      if (!(feed > 0 && feed <= 100000)) throw ApiError{400, "bad_request", "feed: must be > 0 and <= 100000 mm/min"};
      if (auto r = s.jog_start(dir, feed, 0.3); !r) throw ApiError{409, "refused", r.reason};
      m->jog_ws_client = c.id;
      ack();
      return;
    }
    throw ApiError{400, "bad_request", "unknown message type '" + type.substr(0, 40) + "'"};
  } catch (const ApiError& e) {
    reply_error(e.code, e.message);
  } catch (const json::exception& e) {
    reply_error("bad_request", e.what());
  }
}

}  // namespace cncstream::daemon
