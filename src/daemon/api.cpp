#include "cncstream/daemon/api.hpp"

#include <spdlog/spdlog.h>

#include "cncstream/daemon/body_fields.hpp"
#include "cncstream/daemon/precheck.hpp"
#include "cncstream/daemon/ws_message.hpp"

namespace cncstream::daemon {

using nlohmann::json;

Api::Api(boost::asio::io_context& io, boost::asio::thread_pool& pool, const DaemonConfig& config, Auth& auth,
         FileStore& files, Machines& machines, JobManager& jobs, WsHub& hub, std::filesystem::path web_root,
         ShopLink* shop)
    : io_(io),
      pool_(pool),
      config_(config),
      auth_(auth),
      files_(files),
      machines_(machines),
      jobs_(jobs),
      hub_(hub),
      web_root_(std::move(web_root)),
      shop_(shop) {
  add_routes();
}

Machine& Api::machine(const Request& r, std::size_t param) {
  Machine* m = param < r.params.size() ? machines_.find(r.params[param]) : nullptr;
  if (!m) throw ApiError{404, "not_found", "no machine '" + (param < r.params.size() ? r.params[param].substr(0, 64) : "") + "'"};
  return *m;
}

std::int64_t Api::job_id(const Request& r) const { return job_id_param(r.params.at(0)); }

std::optional<Response> Api::precheck(Request& r, bool ws) { return precheck_request(router_, auth_, config_.limits, r, ws); }

void Api::handle(Request r, const Respond& respond) {
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
  router_.add("GET", "/api/v1/health", [](Request&, const Respond& res) {
    res(Response::json(200, {{"ok", true}, {"version", "0.1.0"}}));
  }, true);
  router_.add("GET", "/api/v1/openapi.json", [](Request&, const Respond& res) {
    Response r;
    r.body = openapi_json();
    res(std::move(r));
  });
  router_.add("POST", "/api/v1/ws-token", [this](Request&, const Respond& res) {
    res(Response::json(200, {{"token", auth_.issue_ws_token()}, {"expires_in_s", 30}}));
  });
  // The upgrade itself is taken by the server; a plain GET gets told so.
  router_.add("GET", "/api/v1/ws", [](Request&, const Respond& res) {
    res(Response::error(400, "bad_request", "/api/v1/ws is a WebSocket: send an Upgrade request"));
  });
  machine_routes();
  routine_routes();
  file_routes();
  job_routes();
  tool_routes();
  shop_routes();
  static_routes();
}

// ---- WebSocket --------------------------------------------------------------

std::shared_ptr<WsClient> Api::ws_open(const Request& upgrade, std::weak_ptr<WsPeer> peer) {
  auto c = hub_.add(upgrade.client_id, std::move(peer));
  if (!c) return nullptr;
  hub_.send(*c, WsHub::frame(dump_json(json{{"type", "hello"}, {"client_id", upgrade.client_id},
                                            {"machines", machines_.names()}, {"version", "0.1.0"}})));
  return c;
}

void Api::ws_close(WsClient& c) {
  const std::string cid = c.client_id;
  const auto id = c.id;
  hub_.remove(id);
  machines_.client_gone(cid, id);
}

void Api::ws_message(WsClient& c, const std::string& text) {
  json id = nullptr;
  auto send = [&](const json& j) { hub_.send(c, WsHub::frame(dump_json(j))); };
  auto reply_error = [&](const ApiError& e) {
    send(json{{"type", "error"}, {"id", id}, {"code", e.code}, {"message", e.message}});
  };
  WsMessage msg;
  try {
    msg = parse_ws_message(text);
  } catch (const WsMessageError& e) {
    id = e.id;
    reply_error(e.error);
    return;
  }
  id = msg.id;
  machines_.touch(c.client_id);
  const std::string& type = msg.type;
  auto ack = [&] { send(json{{"type", "ack"}, {"id", id}}); };
  try {
    if (type == "ping") {
      send(json{{"type", "pong"}, {"id", id}});
      return;
    }
    if (type == "subscribe") {
      std::set<std::string> set;
      bool all = false;
      for (const auto& n : msg.machines) {
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
    // jog_start, jog_renew, jog_release
    Machine* m = machines_.find(msg.machine);
    if (!m) throw ApiError{404, "not_found", "no machine '" + msg.machine.substr(0, 64) + "'"};
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
    if (auto r = s.jog_start(msg.dir, msg.feed, 0.3); !r) throw ApiError{409, "refused", r.reason};
    m->jog_ws_client = c.id;
    ack();
  } catch (const ApiError& e) {
    reply_error(e);
  } catch (const json::exception& e) {
    reply_error(ApiError{400, "bad_request", e.what()});
  }
}

}  // namespace cncstream::daemon
