#include "cncstream/daemon/file_store.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <fstream>
#include <sstream>

#include "cncstream/daemon/auth.hpp"
#include "cncstream/geometry/stl.hpp"
#include "cncstream/transport/journal.hpp"
#include "cncstream/transport/sha256.hpp"

namespace cncstream::daemon {

namespace fs = std::filesystem;

namespace {
// The length of the UTF-8 character starting at s[i], or 0 when the bytes
// there are not one (a stray continuation byte, an overlong form, a
// surrogate, beyond U+10FFFF, or cut short).
std::size_t utf8_char_length(const std::string& s, std::size_t i) {
  const auto b = [&](std::size_t k) { return i + k < s.size() ? static_cast<unsigned char>(s[i + k]) : 0u; };
  const auto cont = [&](std::size_t k) { return (b(k) & 0xC0) == 0x80; };
  const unsigned c = b(0);
  if (c < 0x80) return 1;
  if (c >= 0xC2 && c <= 0xDF) return cont(1) ? 2 : 0;
  if (c >= 0xE0 && c <= 0xEF) {
    const unsigned lo = c == 0xE0 ? 0xA0 : 0x80, hi = c == 0xED ? 0x9F : 0xBF;
    return b(1) >= lo && b(1) <= hi && cont(2) ? 3 : 0;
  }
  if (c >= 0xF0 && c <= 0xF4) {
    const unsigned lo = c == 0xF0 ? 0x90 : 0x80, hi = c == 0xF4 ? 0x8F : 0xBF;
    return b(1) >= lo && b(1) <= hi && cont(2) && cont(3) ? 4 : 0;
  }
  return 0;
}
}  // namespace

std::string sanitize_label(const std::string& name) {
  std::string out;
  for (std::size_t i = 0; i < name.size();) {
    const std::size_t n = utf8_char_length(name, i);
    const auto u = static_cast<unsigned char>(name[i]);
    if (n == 0 || u < 0x20 || u == 0x7f || u == '/' || u == '\\') {
      if (out.size() + 1 > 255) break;
      out.push_back('_');
      i += n == 0 ? 1 : n;
      continue;
    }
    if (out.size() + n > 255) break;
    out.append(name, i, n);
    i += n;
  }
  if (out.empty() || out == "." || out == "..") out = "unnamed";
  return out;
}

bool is_file_id(const std::string& s) {
  return s.size() == 64 && std::all_of(s.begin(), s.end(), [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

FileStore::FileStore(fs::path dir) : dir_(std::move(dir)) {
  fs::create_directories(dir_ / "tmp");
  // Spooled uploads of a daemon that died are garbage.
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir_ / "tmp", ec)) fs::remove(e.path(), ec);
}

fs::path FileStore::temp_path() { return dir_ / "tmp" / (random_token_hex(12) + ".part"); }

namespace {

// G-code: printable ASCII, tabs and line ends only; returns the line count.
std::optional<std::size_t> gcode_lines(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  char buf[1 << 16];
  std::size_t lines = 0;
  bool any = false, last_nl = true;
  while (in) {
    in.read(buf, sizeof buf);
    const auto n = in.gcount();
    for (std::streamsize i = 0; i < n; ++i) {
      const auto c = static_cast<unsigned char>(buf[i]);
      if (c == '\n') ++lines;
      else if (c != '\r' && c != '\t' && (c < 0x20 || c > 0x7e)) return std::nullopt;
      any = true;
      last_nl = c == '\n';
    }
  }
  if (!any) return std::nullopt;
  return lines + (last_nl ? 0 : 1);
}

}  // namespace

std::pair<FileInfo, bool> FileStore::ingest(const fs::path& temp, const std::string& label) {
  FileInfo f;
  f.name = sanitize_label(label);
  f.size = fs::file_size(temp);
  f.uploaded_at = transport::Journal::now_iso8601();
  f.id = transport::sha256_file(temp);
  try {
    const auto stl = geometry::load_stl(temp);
    f.kind = "stl";
    f.facets = stl.mesh.size();
    const geometry::Box3 b = stl.mesh.bounds();
    f.bbox = {b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z};
  } catch (const std::exception& stl_error) {
    const auto lines = gcode_lines(temp);
    if (!lines) {
      std::error_code ec;
      fs::remove(temp, ec);
      throw FileStoreError(415, "unsupported_media",
                           "'" + f.name + "' is neither an STL (" + stl_error.what() + ") nor G-code text");
    }
    f.kind = "gcode";
    f.lines = *lines;
  }
  std::lock_guard lock(mu_);
  const fs::path target = dir_ / f.id;
  const bool existed = fs::exists(target);
  std::error_code ec;
  if (existed) fs::remove(temp, ec);
  else fs::rename(temp, target);
  write_meta(f);
  return {f, !existed};
}

void FileStore::write_meta(const FileInfo& f) const {
  const nlohmann::json j = {{"id", f.id}, {"name", f.name}, {"kind", f.kind}, {"size", f.size},
                            {"facets", f.facets}, {"lines", f.lines}, {"uploaded_at", f.uploaded_at}, {"bbox", f.bbox}};
  const fs::path tmp = dir_ / "tmp" / (f.id + ".json.part");
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << j.dump();
  }
  fs::rename(tmp, dir_ / (f.id + ".json"));
}

std::optional<FileInfo> FileStore::read_meta(const std::string& id) const {
  if (!is_file_id(id)) return std::nullopt;
  std::ifstream in(dir_ / (id + ".json"), std::ios::binary);
  if (!in || !fs::exists(dir_ / id)) return std::nullopt;
  try {
    const auto j = nlohmann::json::parse(in);
    FileInfo f;
    f.id = id;
    f.name = j.at("name").get<std::string>();
    f.kind = j.at("kind").get<std::string>();
    f.size = j.at("size").get<std::uint64_t>();
    f.facets = j.value("facets", std::size_t(0));
    f.lines = j.value("lines", std::size_t(0));
    f.uploaded_at = j.value("uploaded_at", std::string());
    if (j.contains("bbox")) f.bbox = j.at("bbox").get<std::array<double, 6>>();
    return f;
  } catch (const std::exception&) {
    return std::nullopt;  // a damaged sidecar: the file is not listed
  }
}

std::vector<FileInfo> FileStore::list() const {
  std::lock_guard lock(mu_);
  std::vector<FileInfo> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir_, ec)) {
    const std::string n = e.path().filename().string();
    if (is_file_id(n))
      if (auto f = read_meta(n)) out.push_back(std::move(*f));
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.uploaded_at > b.uploaded_at; });
  return out;
}

std::optional<FileInfo> FileStore::get(const std::string& id) const {
  std::lock_guard lock(mu_);
  return read_meta(id);
}

bool FileStore::remove(const std::string& id) {
  if (!is_file_id(id)) return false;
  std::lock_guard lock(mu_);
  std::error_code ec;
  const bool had = fs::remove(dir_ / id, ec);
  fs::remove(dir_ / (id + ".json"), ec);
  return had;
}

std::optional<fs::path> FileStore::content_path(const std::string& id) const {
  if (!is_file_id(id)) return std::nullopt;
  const fs::path p = dir_ / id;
  if (!fs::exists(p)) return std::nullopt;
  return p;
}

}  // namespace cncstream::daemon
