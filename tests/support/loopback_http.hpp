#pragma once
// A tiny blocking HTTP/1.1 client over POSIX sockets on the loopback
// interface, for tests that talk to the daemon (no Beast in the tests: it is
// slow to compile).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdlib>
#include <map>
#include <sstream>
#include <string>

namespace loopback {

using nlohmann::json;

inline int connect_to(unsigned short port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return -1;
  }
  int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  return fd;
}

inline bool send_all(int fd, const std::string& s) {
  std::size_t off = 0;
  while (off < s.size()) {
    const ssize_t n = ::send(fd, s.data() + off, s.size() - off, MSG_NOSIGNAL);
    if (n <= 0) return false;
    off += static_cast<std::size_t>(n);
  }
  return true;
}

// Reads until EOF or timeout.
inline std::string read_all(int fd, double timeout_s) {
  std::string out;
  char buf[65536];
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (true) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(end - std::chrono::steady_clock::now()).count();
    if (left <= 0) break;
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(left)) <= 0) break;
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n <= 0) break;
    out.append(buf, static_cast<std::size_t>(n));
  }
  return out;
}

struct HttpResult {
  int status = 0;
  std::map<std::string, std::string> headers;  // lower-case names
  std::string body;
  json j() const { return json::parse(body); }
};

inline HttpResult parse_response(const std::string& raw) {
  HttpResult r;
  const auto end = raw.find("\r\n\r\n");
  if (raw.size() < 12 || end == std::string::npos) return r;
  r.status = std::atoi(raw.substr(9, 3).c_str());
  std::istringstream h(raw.substr(0, end));
  std::string line;
  std::getline(h, line);
  while (std::getline(h, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto c = line.find(':');
    if (c == std::string::npos) continue;
    std::string k = line.substr(0, c);
    for (auto& ch : k) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    std::string v = line.substr(c + 1);
    while (!v.empty() && v.front() == ' ') v.erase(0, 1);
    r.headers[k] = v;
  }
  r.body = raw.substr(end + 4);
  return r;
}

struct Http {
  unsigned short port = 0;
  std::map<std::string, std::string> headers;  // sent with every request
  HttpResult request(const std::string& method, const std::string& target, const std::string& body = "",
                     std::map<std::string, std::string> extra = {}, double timeout_s = 30) const {
    const int fd = connect_to(port);
    if (fd < 0) return {};
    std::string req = method + " " + target + " HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) +
                      "\r\nConnection: close\r\n";
    auto all = headers;
    for (auto& [k, v] : extra) all[k] = v;
    for (auto& [k, v] : all) req += k + ": " + v + "\r\n";
    if (method != "GET" || !body.empty()) req += "Content-Length: " + std::to_string(body.size()) + "\r\n";
    if (!body.empty() && !all.count("Content-Type")) req += "Content-Type: application/json\r\n";
    req += "\r\n" + body;
    send_all(fd, req);
    const std::string raw = read_all(fd, timeout_s);
    ::close(fd);
    return parse_response(raw);
  }
  HttpResult get(const std::string& t) const { return request("GET", t); }
  HttpResult post(const std::string& t, const json& b = json::object()) const { return request("POST", t, b.dump()); }
  HttpResult del(const std::string& t) const { return request("DELETE", t); }
};

}  // namespace loopback
