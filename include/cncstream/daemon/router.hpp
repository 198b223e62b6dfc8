#pragma once
// The one table of routes: method + path pattern ("/api/v1/jobs/{id}",
// "/static/*" for the rest of a path) -> handler. The OpenAPI document is
// checked against this table by a test, so the two cannot drift apart.
#include <functional>
#include <map>
#include <optional>
#include <string_view>
#include <string>
#include <vector>

#include "cncstream/daemon/http_types.hpp"

namespace cncstream::daemon {

using Handler = std::function<void(Request&, Respond)>;

struct Route {
  std::string method;
  std::string pattern;
  Handler handler;
  bool public_route = false;  // served without the token (the page, health)
};

class Router {
 public:
  void add(std::string method, std::string pattern, Handler h, bool public_route = false);
  // Fills r.params. nullptr + status 404 or 405 when nothing matches.
  const Route* match(Request& r, int& status) const;
  const std::vector<Route>& routes() const { return routes_; }

 private:
  std::vector<Route> routes_;
};

// Decodes %XX and (in queries) '+'. nullopt for a bad escape or a NUL byte.
std::optional<std::string> percent_decode(std::string_view s, bool plus_is_space);
// "/path?a=1&b=2" -> path and query (decoded); false when anything is malformed.
bool split_target(std::string_view target, std::string& path, std::map<std::string, std::string>& query);

// Splits "/a/b/c" into {"a", "b", "c"}.
std::vector<std::string> split_path(const std::string& path);

}  // namespace cncstream::daemon
