#pragma once
// The API v1 (docs/api-v1.md): the routes and their handlers, the checks
// every request passes before its body is read, and the WebSocket messages.
// Handlers run on the event loop's thread; anything slow is posted to the
// worker pool and answers later.
#include <boost/asio/io_context.hpp>
#include <boost/asio/thread_pool.hpp>

#include <memory>
#include <optional>
#include <string>

#include "cncstream/daemon/auth.hpp"
#include "cncstream/daemon/config.hpp"
#include "cncstream/daemon/file_store.hpp"
#include "cncstream/daemon/http_types.hpp"
#include "cncstream/daemon/job_manager.hpp"
#include "cncstream/daemon/json_body.hpp"
#include "cncstream/daemon/machines.hpp"
#include "cncstream/daemon/precheck.hpp"
#include "cncstream/daemon/router.hpp"
#include "cncstream/daemon/static_files.hpp"
#include "cncstream/daemon/ws_hub.hpp"

namespace cncstream::daemon {

// The embedded OpenAPI document (src/daemon/openapi.json).
const std::string& openapi_json();

class ShopLink;

class Api {
 public:
  // `shop`: nullptr when the daemon has not joined a shop.
  Api(boost::asio::io_context& io, boost::asio::thread_pool& pool, const DaemonConfig& config, Auth& auth,
      FileStore& files, Machines& machines, JobManager& jobs, WsHub& hub, std::filesystem::path web_root,
      ShopLink* shop = nullptr);

  // Before the body is read: route exists, token, Origin/Host, client id,
  // and for an upload its declared size. nullopt: go on.
  std::optional<Response> precheck(Request& r, bool websocket_upgrade);
  bool is_upload(const Request& r) const { return daemon::is_upload(r); }
  void handle(Request r, const Respond& respond);

  // WebSocket clients.
  std::shared_ptr<WsClient> ws_open(const Request& upgrade, std::weak_ptr<WsPeer> peer);
  void ws_message(WsClient& c, const std::string& text);
  void ws_close(WsClient& c);

  const Router& router() const { return router_; }
  const DaemonConfig& config() const { return config_; }

 private:
  void add_routes();
  void machine_routes();
  void routine_routes();
  void file_routes();
  void job_routes();
  void tool_routes();
  void shop_routes();
  void shop_act_routes();
  void static_routes();
  Machine& machine(const Request& r, std::size_t param = 0);
  std::int64_t job_id(const Request& r) const;

  boost::asio::io_context& io_;
  boost::asio::thread_pool& pool_;
  const DaemonConfig& config_;
  Auth& auth_;
  FileStore& files_;
  Machines& machines_;
  JobManager& jobs_;
  WsHub& hub_;
  std::filesystem::path web_root_;
  ShopLink* shop_;
  Router router_;
};

}  // namespace cncstream::daemon
