#include "cncstream/daemon/router.hpp"

namespace cncstream::daemon {

std::optional<std::string> percent_decode(std::string_view s, bool plus_is_space) {
  std::string out;
  out.reserve(s.size());
  auto hex = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
  };
  for (std::size_t i = 0; i < s.size(); ++i) {
    char c = s[i];
    if (c == '%') {
      if (i + 2 >= s.size()) return std::nullopt;
      const int a = hex(s[i + 1]), b = hex(s[i + 2]);
      if (a < 0 || b < 0) return std::nullopt;
      c = static_cast<char>(a * 16 + b);
      i += 2;
    } else if (c == '+' && plus_is_space) {
      c = ' ';
    }
    if (c == '\0') return std::nullopt;
    out.push_back(c);
  }
  return out;
}

bool split_target(std::string_view target, std::string& path, std::map<std::string, std::string>& query) {
  const auto q = target.find('?');
  const auto p = percent_decode(target.substr(0, q), false);
  if (!p || p->empty() || p->front() != '/') return false;
  path = *p;
  query.clear();
  if (q == std::string_view::npos) return true;
  std::string_view rest = target.substr(q + 1);
  while (!rest.empty()) {
    const auto amp = rest.find('&');
    const std::string_view item = rest.substr(0, amp);
    const auto eq = item.find('=');
    const auto k = percent_decode(item.substr(0, eq), true);
    const auto v = eq == std::string_view::npos ? std::optional<std::string>("") : percent_decode(item.substr(eq + 1), true);
    if (!k || !v) return false;
    if (!k->empty()) query[*k] = *v;
    if (amp == std::string_view::npos) break;
    rest = rest.substr(amp + 1);
  }
  return true;
}

std::vector<std::string> split_path(const std::string& path) {
  std::vector<std::string> out;
  std::size_t i = 0;
  while (i < path.size()) {
    while (i < path.size() && path[i] == '/') ++i;
    const std::size_t j = path.find('/', i);
    const std::size_t end = j == std::string::npos ? path.size() : j;
    if (end > i) out.push_back(path.substr(i, end - i));
    i = end;
  }
  return out;
}

void Router::add(std::string method, std::string pattern, Handler h, bool public_route) {
  routes_.push_back(Route{std::move(method), std::move(pattern), std::move(h), public_route});
}

namespace {
bool match_pattern(const std::string& pattern, const std::string& path, std::vector<std::string>& params) {
  const auto ps = split_path(pattern), xs = split_path(path);
  params.clear();
  for (std::size_t i = 0; i < ps.size(); ++i) {
    if (ps[i] == "*") {
      // The rest of the path, re-joined ("" for the bare prefix).
      std::string rest;
      for (std::size_t k = i; k < xs.size(); ++k) rest += (k > i ? "/" : "") + xs[k];
      params.push_back(rest);
      return true;
    }
    if (i >= xs.size()) return false;
    if (ps[i].size() > 2 && ps[i].front() == '{' && ps[i].back() == '}') params.push_back(xs[i]);
    else if (ps[i] != xs[i]) return false;
  }
  return ps.size() == xs.size();
}
}  // namespace

const Route* Router::match(Request& r, int& status) const {
  bool path_matched = false;
  std::vector<std::string> params;
  for (const auto& route : routes_) {
    if (!match_pattern(route.pattern, r.path, params)) continue;
    path_matched = true;
    if (route.method == r.method || (r.method == "HEAD" && route.method == "GET")) {
      r.params = params;
      status = 200;
      return &route;
    }
  }
  status = path_matched ? 405 : 404;
  return nullptr;
}

}  // namespace cncstream::daemon
