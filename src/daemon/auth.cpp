#include "cncstream/daemon/auth.hpp"

#include <fmt/core.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <system_error>

namespace cncstream::daemon {

bool constant_time_equal(const std::string& a, const std::string& b) {
  // The length of the real token is no secret (always 64); differing lengths
  // still walk the whole presented string so timing says nothing of content.
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  const std::size_t n = a.size();
  for (std::size_t i = 0; i < n; ++i) {
    const unsigned char cb = i < b.size() ? static_cast<unsigned char>(b[i]) : 0;
    diff |= static_cast<unsigned char>(static_cast<unsigned char>(a[i]) ^ cb);
  }
  return diff == 0;
}

std::string random_token_hex(std::size_t bytes) {
  std::string raw(bytes, '\0');
  const int fd = ::open("/dev/urandom", O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error(std::string("/dev/urandom: ") + std::generic_category().message(errno));
  std::size_t got = 0;
  while (got < bytes) {
    const ssize_t n = ::read(fd, raw.data() + got, bytes - got);
    if (n <= 0) {
      ::close(fd);
      throw std::runtime_error("/dev/urandom: short read");
    }
    got += static_cast<std::size_t>(n);
  }
  ::close(fd);
  static const char* hex = "0123456789abcdef";
  std::string out;
  out.reserve(bytes * 2);
  for (unsigned char c : raw) {
    out.push_back(hex[c >> 4]);
    out.push_back(hex[c & 15]);
  }
  return out;
}

std::string load_or_create_token(const std::filesystem::path& data_dir, bool& created) {
  created = false;
  std::filesystem::create_directories(data_dir);
  const auto path = data_dir / "token";
  struct stat st{};
  if (::stat(path.c_str(), &st) == 0) {
    if (st.st_mode & (S_IRWXG | S_IRWXO)) {
      const std::string mode = fmt::format("{:03o}", static_cast<unsigned>(st.st_mode & 0777));
      throw std::runtime_error(cat({path.string(), ": the token file is open to others (mode ", mode, "); chmod 600 it"}));
    }
    std::ifstream in(path);
    std::string t;
    std::getline(in, t);
    if (t.size() < 32) throw std::runtime_error(path.string() + ": the token file is empty or too short");
    return t;
  }
  std::string t = random_token_hex();
  // O_EXCL + 0600 at creation: never a moment where the file is readable by others.
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) throw std::runtime_error(path.string() + ": cannot create the token file: " + std::generic_category().message(errno));
  const std::string line = t + "\n";
  const bool ok = ::write(fd, line.data(), line.size()) == static_cast<ssize_t>(line.size()) && ::fsync(fd) == 0;
  ::close(fd);
  if (!ok) throw std::runtime_error(path.string() + ": cannot write the token file");
  created = true;
  return t;
}

Auth::Auth(const DaemonConfig& config, std::string token)
    : required_(config.token_required()),
      token_(std::move(token)),
      origins_(config.security.allowed_origins),
      hosts_(config.security.allowed_hosts) {}

namespace {
std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}
// "host:port" / "[::1]:port" -> host
std::string host_name(const std::string& host_header) {
  std::string h = lower(host_header);
  if (!h.empty() && h.front() == '[') {
    const auto e = h.find(']');
    return e == std::string::npos ? h : h.substr(1, e - 1);
  }
  const auto c = h.rfind(':');
  return c == std::string::npos ? h : h.substr(0, c);
}
}  // namespace

bool Auth::host_allowed(const Request& r) const {
  const std::string host = r.header("host");
  const std::string name = host_name(host);
  if (name == "localhost" || name == "127.0.0.1" || name == "::1") return true;
  for (const auto& h : hosts_)
    if (lower(h) == name || lower(h) == lower(host)) return true;
  return false;
}

bool Auth::origin_allowed(const Request& r) const {
  const auto it = r.headers.find("origin");
  if (it == r.headers.end()) return true;  // not a browser's cross-site request
  const std::string origin = lower(it->second);
  if (origin == "null" || origin.empty()) return false;
  const std::string host = lower(r.header("host"));
  if (!host.empty() && (origin == "http://" + host || origin == "https://" + host)) return true;
  for (const auto& o : origins_)
    if (lower(o) == origin) return true;
  return false;
}

bool Auth::consume_ws_token(const std::string& t) {
  std::lock_guard lock(mu_);
  const auto now = std::chrono::steady_clock::now();
  std::erase_if(ws_tokens_, [&](const auto& e) { return e.second < now; });
  // Compare against each in constant time (there are few).
  for (auto it = ws_tokens_.begin(); it != ws_tokens_.end(); ++it)
    if (constant_time_equal(it->first, t)) {
      ws_tokens_.erase(it);
      return true;
    }
  return false;
}

std::string Auth::issue_ws_token(std::chrono::seconds ttl) {
  std::string t = random_token_hex(24);
  std::lock_guard lock(mu_);
  if (ws_tokens_.size() > 1000) ws_tokens_.erase(ws_tokens_.begin());  // bounded: a client cannot grow it
  ws_tokens_[t] = std::chrono::steady_clock::now() + ttl;
  return t;
}

std::optional<Response> Auth::check(const Request& r, bool ws) {
  const bool state_changing = r.method != "GET" && r.method != "HEAD" && r.method != "OPTIONS";
  if ((state_changing || ws) && !origin_allowed(r))
    return Response::error(403, "forbidden_origin",
                           "Origin '" + r.header("origin") + "' may not send requests to this daemon");
  if (!required_) {
    if (!host_allowed(r))
      return Response::error(403, "forbidden_origin",
                             "Host '" + r.header("host") + "' is not this daemon's (add it to security.allowed_hosts)");
    return std::nullopt;
  }
  const std::string auth = r.header("authorization");
  static const std::string bearer = "Bearer ";
  if (auth.size() > bearer.size() && auth.compare(0, bearer.size(), bearer) == 0 &&
      constant_time_equal(token_, auth.substr(bearer.size())))
    return std::nullopt;
  if (ws) {
    if (const auto t = r.query_value("token"); t && consume_ws_token(*t)) return std::nullopt;
  }
  Response e = Response::error(401, "unauthorized",
                               auth.empty() ? "this daemon needs 'Authorization: Bearer <token>' (see <data>/token)"
                                            : "wrong token");
  e.headers.emplace_back("WWW-Authenticate", "Bearer");
  return e;
}

}  // namespace cncstream::daemon
