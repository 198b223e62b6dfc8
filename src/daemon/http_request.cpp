#include "http_request.hpp"

#include <cctype>
#include <string_view>

#include "cncstream/daemon/router.hpp"

namespace cncstream::daemon {

Request request_from(const boost::beast::http::request_header<>& h, bool& ok) {
  Request r;
  r.method = std::string(h.method_string());
  ok = split_target(std::string_view(h.target().data(), h.target().size()), r.path, r.query);
  for (const auto& f : h) {
    std::string name(f.name_string());
    for (auto& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    r.headers[name] = std::string(f.value());
  }
  return r;
}

}  // namespace cncstream::daemon
