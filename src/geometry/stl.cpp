#include "cncstream/geometry/stl.hpp"

#include <bit>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>
#include <system_error>
#include <unordered_map>

namespace cncstream::geometry {

LengthUnit parse_length_unit(const std::string& s) {
  if (s == "mm") return LengthUnit::Millimetre;
  if (s == "in" || s == "inch") return LengthUnit::Inch;
  if (s == "m") return LengthUnit::Metre;
  throw std::invalid_argument("unknown unit '" + s + "' (expected mm, in or m)");
}

double unit_to_mm(LengthUnit u) {
  switch (u) {
    case LengthUnit::Millimetre: return 1.0;
    case LengthUnit::Inch: return 25.4;
    case LengthUnit::Metre: return 1000.0;
  }
  return 1.0;
}

namespace {

// Welds vertices on exact (post-scale) coordinate equality and drops
// zero-area facets.
class MeshBuilder {
 public:
  explicit MeshBuilder(double scale) : scale_(scale) {}

  void reserve(std::size_t facets) {
    mesh_.triangles.reserve(facets);
    mesh_.vertices.reserve(facets / 2 + 3);
    index_.reserve(facets / 2 + 3);
  }

  void add(const Vec3 (&p)[3]) {
    ++read_;
    std::array<std::uint32_t, 3> t{};
    Vec3 q[3];
    for (int k = 0; k < 3; ++k) {
      q[k] = p[k] * scale_;
      t[k] = vertex(q[k]);
    }
    const Vec3 e1 = q[1] - q[0], e2 = q[2] - q[0];
    const double l = std::fmax(dot(e1, e1), dot(e2, e2));
    const Vec3 c = cross(e1, e2);
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || dot(c, c) <= 1e-28 * l * l) {
      ++dropped_;
      return;
    }
    mesh_.triangles.push_back(t);
  }

  StlLoadResult finish() && {
    StlLoadResult r;
    r.facets_read = read_;
    r.dropped_degenerate = dropped_;
    r.mesh = std::move(mesh_);
    return r;
  }

 private:
  struct Key {
    std::uint64_t x, y, z;
    bool operator==(const Key&) const = default;
  };
  struct KeyHash {
    std::size_t operator()(const Key& k) const {
      std::uint64_t h = k.x * 0x9E3779B97F4A7C15ull;
      h ^= k.y + 0x7F4A7C159E3779B9ull + (h << 6) + (h >> 2);
      h ^= k.z + 0x94D049BB133111EBull + (h << 6) + (h >> 2);
      return static_cast<std::size_t>(h ^ (h >> 31));
    }
  };
  static std::uint64_t bits(double v) { return std::bit_cast<std::uint64_t>(v == 0.0 ? 0.0 : v); }

  std::uint32_t vertex(const Vec3& v) {
    const Key k{bits(v.x), bits(v.y), bits(v.z)};
    auto [it, inserted] = index_.try_emplace(k, static_cast<std::uint32_t>(mesh_.vertices.size()));
    if (inserted) mesh_.vertices.push_back(v);
    return it->second;
  }

  double scale_;
  Mesh mesh_;
  std::unordered_map<Key, std::uint32_t, KeyHash> index_;
  std::size_t read_ = 0, dropped_ = 0;
};

[[noreturn]] void fail(const std::string& name, const std::string& where, const std::string& what) {
  throw StlError(name + ":" + where + ": " + what);
}

float read_f32(const char* p) {
  std::uint32_t u;
  std::memcpy(&u, p, 4);
  if constexpr (std::endian::native == std::endian::big) u = __builtin_bswap32(u);
  return std::bit_cast<float>(u);
}

std::uint32_t read_u32(const char* p) {
  std::uint32_t u;
  std::memcpy(&u, p, 4);
  if constexpr (std::endian::native == std::endian::big) u = __builtin_bswap32(u);
  return u;
}

StlLoadResult parse_binary(const std::string& bytes, const std::string& name, double scale) {
  const std::uint32_t n = read_u32(bytes.data() + 80);
  MeshBuilder b(scale);
  b.reserve(n);
  for (std::uint32_t f = 0; f < n; ++f) {
    const std::size_t base = 84 + std::size_t{f} * 50;
    Vec3 p[3];
    for (int k = 0; k < 3; ++k) {
      double c[3];
      for (int a = 0; a < 3; ++a) {
        const std::size_t off = base + 12 + std::size_t(k) * 12 + std::size_t(a) * 4;
        const float v = read_f32(bytes.data() + off);
        if (!std::isfinite(v)) {
          fail(name, "byte " + std::to_string(off),
               std::string(std::isnan(v) ? "NaN" : "infinite") + " coordinate in facet " +
                   std::to_string(f + 1) + " of " + std::to_string(n));
        }
        c[a] = v;
      }
      p[k] = {c[0], c[1], c[2]};
    }
    b.add(p);
  }
  StlLoadResult r = std::move(b).finish();
  r.binary = true;
  const auto hdr = bytes.substr(0, 80);
  r.solid_name = hdr.substr(0, hdr.find('\0'));
  return r;
}

// Tokenizer over ASCII STL that remembers each token's line.
class AsciiReader {
 public:
  AsciiReader(const std::string& s, const std::string& name) : s_(s), name_(name) {}

  struct Token {
    std::string_view text;
    std::size_t line;
  };

  std::optional<Token> next() {
    while (pos_ < s_.size()) {
      const char c = s_[pos_];
      if (c == '\n') { ++line_; ++pos_; }
      else if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') ++pos_;
      else break;
    }
    if (pos_ >= s_.size()) return std::nullopt;
    const std::size_t start = pos_;
    while (pos_ < s_.size() && !std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
    return Token{std::string_view(s_).substr(start, pos_ - start), line_};
  }

  // Rest of the current line (for solid names), trimmed.
  std::string rest_of_line() {
    const std::size_t start = pos_;
    while (pos_ < s_.size() && s_[pos_] != '\n') ++pos_;
    std::string r = s_.substr(start, pos_ - start);
    const auto b = r.find_first_not_of(" \t\r");
    const auto e = r.find_last_not_of(" \t\r");
    return b == std::string::npos ? std::string() : r.substr(b, e - b + 1);
  }

  std::size_t line() const { return line_; }

  [[noreturn]] void error(std::size_t line, const std::string& what) const {
    fail(name_, "line " + std::to_string(line), what);
  }

  Token expect_word(const char* word, const char* context) {
    auto t = next();
    if (!t) error(line_, std::string("unexpected end of file: expected '") + word + "' " + context);
    if (!iequals(t->text, word))
      error(t->line, std::string("expected '") + word + "' " + context + ", found '" +
                         std::string(t->text) + "'");
    return *t;
  }

  double expect_number(const char* what) {
    auto t = next();
    if (!t) error(line_, std::string("unexpected end of file: expected ") + what);
    double v = 0;
    const char* b = t->text.data();
    const char* e = b + t->text.size();
    if (b != e && *b == '+') ++b;  // from_chars does not take a leading '+'
    auto [p, ec] = std::from_chars(b, e, v);
    if (ec != std::errc() || p != e) {
      if (ec == std::errc::result_out_of_range && p == e) {
        // from_chars does not tell overflow from underflow: strtod does.
        const double big = std::strtod(std::string(t->text).c_str(), nullptr);
        if (!std::isfinite(big) || std::fabs(big) > 1.0)
          error(t->line, std::string("infinite value in ") + what + " ('" + std::string(t->text) + "' overflows)");
        return 0;  // underflow to a denormal: treat as zero
      }
      error(t->line, std::string("expected ") + what + ", found '" + std::string(t->text) + "'");
    }
    if (!std::isfinite(v))
      error(t->line, std::string(std::isnan(v) ? "NaN" : "infinite") + " value in " + what);
    return v;
  }

  static bool iequals(std::string_view a, std::string_view b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
      if (std::tolower(static_cast<unsigned char>(a[i])) != std::tolower(static_cast<unsigned char>(b[i])))
        return false;
    return true;
  }

 private:
  const std::string& s_;
  const std::string& name_;
  std::size_t pos_ = 0;
  std::size_t line_ = 1;
};

StlLoadResult parse_ascii(const std::string& bytes, const std::string& name, double scale) {
  AsciiReader in(bytes, name);
  in.expect_word("solid", "at the start of an ASCII STL");
  std::string solid_name = in.rest_of_line();
  const std::string first_name = solid_name;
  MeshBuilder b(scale);
  b.reserve(bytes.size() / 250);
  for (;;) {
    auto t = in.next();
    if (!t) in.error(in.line(), "unexpected end of file: expected 'facet' or 'endsolid'");
    if (AsciiReader::iequals(t->text, "endsolid")) {
      const std::string end_name = in.rest_of_line();
      // Exporters often shorten the name at `endsolid` ("solid part v2" ...
      // "endsolid part"): only a different first word is a mismatch.
      auto first_word = [](const std::string& n) { return n.substr(0, n.find_first_of(" \t")); };
      if (!end_name.empty() && !solid_name.empty() && first_word(end_name) != first_word(solid_name))
        in.error(t->line, "'endsolid " + end_name + "' does not match 'solid " + solid_name + "'");
      auto extra = in.next();
      if (!extra) break;
      // Some exporters write several solids into one file: read them all.
      if (!AsciiReader::iequals(extra->text, "solid"))
        in.error(extra->line, "unexpected '" + std::string(extra->text) + "' after 'endsolid'");
      solid_name = in.rest_of_line();
      continue;
    }
    if (!AsciiReader::iequals(t->text, "facet"))
      in.error(t->line, "expected 'facet' or 'endsolid', found '" + std::string(t->text) + "'");
    in.expect_word("normal", "after 'facet'");
    for (int a = 0; a < 3; ++a) in.expect_number("a normal component");
    in.expect_word("outer", "after the facet normal");
    in.expect_word("loop", "after 'outer'");
    Vec3 p[3];
    for (int k = 0; k < 3; ++k) {
      auto vt = in.next();
      if (!vt) in.error(in.line(), "unexpected end of file inside a facet");
      if (!AsciiReader::iequals(vt->text, "vertex"))
        in.error(vt->line, "expected 'vertex' (a facet needs 3), found '" + std::string(vt->text) + "'");
      const double x = in.expect_number("a vertex coordinate");
      const double y = in.expect_number("a vertex coordinate");
      const double z = in.expect_number("a vertex coordinate");
      p[k] = {x, y, z};
    }
    auto el = in.next();
    if (!el) in.error(in.line(), "unexpected end of file: expected 'endloop'");
    if (AsciiReader::iequals(el->text, "vertex"))
      in.error(el->line, "facet has more than 3 vertices (only triangles are allowed)");
    if (!AsciiReader::iequals(el->text, "endloop"))
      in.error(el->line, "expected 'endloop', found '" + std::string(el->text) + "'");
    in.expect_word("endfacet", "after 'endloop'");
    b.add(p);
  }
  StlLoadResult r = std::move(b).finish();
  r.binary = false;
  r.solid_name = first_name;
  return r;
}

// Binary STL bodies are full of zero bytes (zero coordinates, attribute
// words); text has none.
bool looks_like_text(const std::string& bytes) { return bytes.find('\0') == std::string::npos; }

}  // namespace

StlLoadResult parse_stl(const std::string& bytes, const std::string& name, const StlLoadOptions& options) {
  if (!(options.scale > 0) || !std::isfinite(options.scale))
    throw StlError(name + ": scale must be a positive number");
  const double scale = unit_to_mm(options.units) * options.scale;
  if (bytes.empty()) fail(name, "byte 0", "empty file (not an STL)");

  if (bytes.size() >= 84) {
    const std::uint64_t n = read_u32(bytes.data() + 80);
    if (84 + 50 * n == bytes.size()) return parse_binary(bytes, name, scale);
  }
  std::size_t first = bytes.find_first_not_of(" \t\r\n");
  const bool starts_solid = first != std::string::npos && bytes.size() - first >= 5 &&
                            AsciiReader::iequals(std::string_view(bytes).substr(first, 5), "solid");
  if (starts_solid) {
    try {
      return parse_ascii(bytes, name, scale);
    } catch (const StlError&) {
      // A binary file whose header happens to start with "solid" and whose
      // facet count is wrong: the binary diagnosis is the useful one.
      if (looks_like_text(bytes) || bytes.size() < 84) throw;
    }
  }

  if (bytes.size() < 84)
    fail(name, "byte " + std::to_string(bytes.size()),
         "file is too short for a binary STL (" + std::to_string(bytes.size()) +
             " bytes, need at least 84) and is not an ASCII STL");
  const std::uint64_t n = read_u32(bytes.data() + 80);
  fail(name, "byte 80",
       "binary STL facet count says " + std::to_string(n) + " facets, which needs " +
           std::to_string(84 + 50 * n) + " bytes, but the file has " + std::to_string(bytes.size()) +
           " bytes (truncated or corrupt)");
}

StlLoadResult load_stl(const std::filesystem::path& path, const StlLoadOptions& options) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw StlError(path.string() + ": cannot open (" + std::generic_category().message(errno) + ")");
  std::string bytes;
  f.seekg(0, std::ios::end);
  const auto size = f.tellg();
  if (size < 0) throw StlError(path.string() + ": cannot read (not a regular file?)");
  bytes.resize(static_cast<std::size_t>(size));
  f.seekg(0);
  f.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!f) throw StlError(path.string() + ": read error");
  return parse_stl(bytes, path.string(), options);
}

void write_stl_binary(const std::filesystem::path& path, const Mesh& mesh, const std::string& header) {
  std::ofstream f(path, std::ios::binary);
  if (!f) throw StlError(path.string() + ": cannot open for writing (" + std::generic_category().message(errno) + ")");
  char hdr[80] = {};
  header.copy(hdr, 79);
  f.write(hdr, 80);
  auto put_u32 = [&](std::uint32_t v) {
    char b[4];
    std::memcpy(b, &v, 4);
    f.write(b, 4);
  };
  auto put_f32 = [&](double v) {
    const float x = static_cast<float>(v);
    char b[4];
    std::memcpy(b, &x, 4);
    f.write(b, 4);
  };
  put_u32(static_cast<std::uint32_t>(mesh.triangles.size()));
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Vec3 a = mesh.corner(t, 0), b = mesh.corner(t, 1), c = mesh.corner(t, 2);
    const Vec3 nrm = normalized(cross(b - a, c - a));
    put_f32(nrm.x); put_f32(nrm.y); put_f32(nrm.z);
    for (const Vec3& p : {a, b, c}) { put_f32(p.x); put_f32(p.y); put_f32(p.z); }
    const char attr[2] = {0, 0};
    f.write(attr, 2);
  }
  if (!f) throw StlError(path.string() + ": write error");
}

}  // namespace cncstream::geometry
