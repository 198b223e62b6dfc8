// The web page: GET / and /static/<path> from the web root, with content
// types, and nothing outside the root.
#include "cncstream/daemon/static_files.hpp"

#include "cncstream/daemon/api.hpp"

namespace cncstream::daemon {

std::string content_type_for(const std::filesystem::path& p) {
  const std::string e = p.extension().string();
  if (e == ".html" || e == ".htm") return "text/html; charset=utf-8";
  if (e == ".js" || e == ".mjs") return "text/javascript; charset=utf-8";
  if (e == ".css") return "text/css; charset=utf-8";
  if (e == ".svg") return "image/svg+xml";
  if (e == ".png") return "image/png";
  if (e == ".json") return "application/json";
  if (e == ".woff2") return "font/woff2";
  if (e == ".ico") return "image/x-icon";
  if (e == ".txt") return "text/plain; charset=utf-8";
  return "application/octet-stream";
}

std::optional<std::filesystem::path> safe_static_path(const std::filesystem::path& root, const std::string& rel) {
  if (root.empty() || rel.empty() || rel.size() > 512) return std::nullopt;
  for (const auto& part : split_path(rel))
    if (part.empty() || part == ".." || part == "." || part.front() == '.' ||
        part.find_first_of(std::string("\\\0:", 3)) != std::string::npos)
      return std::nullopt;
  if (rel.front() == '/' || rel.find('\\') != std::string::npos || rel.find('\0') != std::string::npos)
    return std::nullopt;
  const auto p = root / rel;
  std::error_code ec;
  // A symlink inside the root that points out of it is refused too.
  const auto canon = std::filesystem::weakly_canonical(p, ec);
  const auto canon_root = std::filesystem::weakly_canonical(root, ec);
  if (ec) return std::nullopt;
  const auto r = canon_root.string(), c = canon.string();
  if (c.compare(0, r.size(), r) != 0 || (c.size() > r.size() && c[r.size()] != '/')) return std::nullopt;
  if (!std::filesystem::is_regular_file(canon, ec)) return std::nullopt;
  return canon;
}

void Api::static_routes() {
  auto serve = [this](const std::string& rel, Respond& res) {
    const auto p = safe_static_path(web_root_, rel);
    if (!p) throw ApiError{404, "not_found", "no such file"};
    Response r;
    r.content_type = content_type_for(*p);
    r.file = *p;
    r.headers.emplace_back("X-Content-Type-Options", "nosniff");
    r.headers.emplace_back("Cache-Control", "no-cache");
    res(std::move(r));
  };
  router_.add("GET", "/", [serve](Request&, Respond res) { serve("index.html", res); }, true);
  router_.add("GET", "/static/*", [serve](Request& r, Respond res) { serve(r.params.at(0), res); }, true);
}

}  // namespace cncstream::daemon
