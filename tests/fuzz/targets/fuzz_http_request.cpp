// Bytes from a client -> what cncstreamd does with a request before any
// machine or job is touched: Beast's parser with the server's limits, the
// Request the handlers see (request_from: target decoded, headers), the
// checks before the body (precheck: route, token, Origin/Host, client id,
// upload size; under both a token-free loopback daemon and one that needs a
// token), the JSON body, and the field checks of the route it matched (the
// same functions its handler calls first). Every answer must serialise.
// The routes are the OpenAPI document's: a daemon test checks that it lists
// exactly the routes the daemon serves.
#include <boost/beast/http/empty_body.hpp>
#include <boost/beast/http/parser.hpp>
#include <boost/beast/http/string_body.hpp>
#include <boost/beast/websocket/rfc6455.hpp>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>

#include "cncstream/daemon/auth.hpp"
#include "cncstream/daemon/body_fields.hpp"
#include "cncstream/daemon/file_store.hpp"
#include "cncstream/daemon/job_params.hpp"
#include "cncstream/daemon/json_body.hpp"
#include "cncstream/daemon/precheck.hpp"
#include "cncstream/daemon/router.hpp"
#include "cncstream/daemon/static_files.hpp"
// Relative: the ordinary test builds include this file from tests/daemon/.
#include "../../../src/daemon/http_request.hpp"

namespace {

namespace http = boost::beast::http;
namespace fs = std::filesystem;
using nlohmann::json;
using namespace cncstream::daemon;

struct HttpFuzzWorld {
  Router router;
  DaemonConfig loopback, remote;
  std::unique_ptr<Auth> loopback_auth, remote_auth;
  fs::path web_root;
  FileInfo part;

  HttpFuzzWorld() {
    std::ifstream in(CNCSTREAM_SOURCE_DIR "/src/daemon/openapi.json");
    const json doc = json::parse(in);
    for (const auto& [path, ops] : doc.at("paths").items())
      for (const auto& [method, op] : ops.items()) {
        std::string m = method;
        for (auto& c : m) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
        const bool open = op.contains("security") && op.at("security").empty();
        router.add(m, path == "/static/{path}" ? "/static/*" : path, [](Request&, Respond) {}, open);
      }
    remote.listen_address = "0.0.0.0";
    remote.security.allowed_origins = {"http://pad.local:8080"};
    remote.security.allowed_hosts = {"cnc.local", "cnc.local:8420"};
    loopback_auth = std::make_unique<Auth>(loopback, "");
    remote_auth = std::make_unique<Auth>(remote, std::string(64, 'a'));
    web_root = fs::temp_directory_path() / ("cncstream_fuzz_web_" + std::to_string(::getpid()));
    fs::create_directories(web_root / "static");
    std::ofstream(web_root / "index.html") << "<!doctype html>";
    std::ofstream(web_root / "static" / "app.js") << "//";
    part.kind = "stl";
    part.bbox = {0, 0, 0, 120, 100, 10};
  }
  ~HttpFuzzWorld() {
    std::error_code ec;
    fs::remove_all(web_root, ec);
  }
};

HttpFuzzWorld& world() {
  static HttpFuzzWorld w;
  return w;
}

// A response as the server would write it: serialising must not throw.
void answer(const Response& r) {
  if (r.body.size() > (1u << 20)) std::abort();
}

// The field checks each route's handler makes before it touches a machine
// or a job (src/daemon/api_*.cpp).
void check_fields(HttpFuzzWorld& w, const Route& route, Request& r) {
  const std::string key = route.method + " " + route.pattern;
  const auto param = [&](std::size_t i) -> const std::string& { return r.params.at(i); };
  if (key == "GET /static/*") {
    (void)safe_static_path(w.web_root, param(0));
    return;
  }
  if (key == "POST /api/v1/files") {
    // The label becomes the file's stored name and is written as JSON.
    const std::string label = sanitize_label(r.query_value("name").value_or("unnamed"));
    (void)json(label).dump();
    return;
  }
  if (route.pattern.rfind("/api/v1/jobs/{id}", 0) == 0) (void)job_id_param(param(0));
  if (route.method != "POST") return;
  const json b = parse_body(r);
  if (key == "POST /api/v1/machines/{m}/control") {
    (void)force_field(b);
  } else if (key == "POST /api/v1/machines/{m}/console") {
    (void)console_line(b);
  } else if (key == "POST /api/v1/machines/{m}/jog") {
    (void)jog_direction(b);
    (void)number_field(b, "distance", 0, 1000);
    (void)number_field(b, "feed", 0, 100000);
  } else if (key == "POST /api/v1/machines/{m}/actions/{action}") {
    if (param(1) == "zero_axes") (void)zero_axes_field(b);
    if (param(1) == "spindle") (void)on_field(b);
  } else if (key == "POST /api/v1/machines/{m}/realtime") {
    (void)override_command(b);
  } else if (key == "POST /api/v1/jobs") {
    // The job manager checks machine and file first, then these.
    if (b.is_object() && b.contains("params")) {
      const auto checked = check_toolpath_params(b.at("params"), w.part, w.loopback.limits);
      (void)checked.canonical.dump();  // the cache key: strict, as the job manager dumps it
    }
  }
}

// Feeds the parser as the server's reads would, until it has what it waits
// for, needs more than there is, or fails. Returns the bytes it took.
template <class Parser, class Done>
std::size_t feed(Parser& p, const std::uint8_t* data, std::size_t size, Done done, boost::beast::error_code& ec) {
  std::size_t used = 0;
  while (!done() && used < size) {
    const std::size_t n = p.put(boost::asio::buffer(data + used, size - used), ec);
    used += n;
    if (ec == http::error::need_more) ec = {};
    if (ec || n == 0) break;
  }
  return used;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  HttpFuzzWorld& w = world();
  boost::beast::error_code ec;
  http::request_parser<http::empty_body> header;
  header.header_limit(static_cast<std::uint32_t>(kMaxHeaderBytes));
  header.body_limit(std::numeric_limits<std::uint64_t>::max());
  header.eager(false);
  std::size_t used = feed(header, data, size, [&] { return header.is_header_done(); }, ec);
  if (ec || !header.is_header_done()) return 0;  // the server answers 400/431, or waits for more
  bool ok = false;
  Request base = request_from(header.get().base(), ok);
  if (!ok) {
    answer(Response::error(400, "bad_request", "malformed request target"));
    return 0;
  }
  const bool upgrade = boost::beast::websocket::is_upgrade(header.get());
  bool passed = false;
  Request r;
  for (Auth* auth : {w.loopback_auth.get(), w.remote_auth.get()}) {
    Request attempt = base;
    if (auto e = precheck_request(w.router, *auth, w.loopback.limits, attempt, upgrade && attempt.path == "/api/v1/ws")) {
      answer(*e);
    } else {
      passed = true;
      r = std::move(attempt);
    }
  }
  if (!passed || upgrade) return 0;
  if (!is_upload(r)) {
    http::request_parser<http::string_body> body(std::move(header));
    body.body_limit(w.loopback.limits.max_json_bytes);
    if (declared_beyond(body.content_length(), w.loopback.limits.max_json_bytes)) {
      answer(Response::error(413, "too_large", "the body exceeds the limit"));
      return 0;
    }
    used += feed(body, data + used, size - used, [&] { return body.is_done(); }, ec);
    if (ec == http::error::body_limit) answer(Response::error(413, "too_large", "the body exceeds the limit"));
    if (ec || !body.is_done()) return 0;
    r.body = body.get().body();
  }
  int status = 0;
  const Route* route = w.router.match(r, status);
  if (!route) std::abort();  // precheck passed: the route exists
  try {
    check_fields(w, *route, r);
  } catch (const ApiError& e) {
    answer(Response::error(e.status, e.code, e.message));
  } catch (const json::exception& e) {
    answer(Response::error(400, "bad_request", std::string("bad JSON value: ") + e.what()));
  }
  return 0;
}
