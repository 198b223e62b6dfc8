// Height-field files: raw float32 data plus a text sidecar.
#include "cncstream/cam/height_field_io.hpp"

#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <system_error>

namespace cncstream::cam {

namespace {

constexpr const char* kMagic = "cncstream height field 1";

std::uint32_t to_little(std::uint32_t v) {
  if constexpr (std::endian::native == std::endian::big)
    return (v >> 24) | ((v >> 8) & 0xff00u) | ((v << 8) & 0xff0000u) | (v << 24);
  return v;
}

std::string num(double v) {
  std::ostringstream o;
  o.precision(17);
  o << v;
  return o.str();
}

}  // namespace

std::filesystem::path height_field_sidecar(const std::filesystem::path& data_path) {
  return std::filesystem::path(data_path.string() + ".txt");
}

HeightFieldWriter::HeightFieldWriter(const std::filesystem::path& data_path, const GridSpec& grid,
                                     std::optional<geometry::Vec3> work_offset, std::optional<geometry::Vec3> work_origin)
    : path_(data_path),
      grid_(grid),
      work_offset_(work_offset),
      work_origin_(work_origin),
      out_(data_path, std::ios::binary) {
  if (!out_) throw HeightFieldError(data_path.string() + ": cannot open for writing (" + std::generic_category().message(errno) + ")");
}

void HeightFieldWriter::append(std::span<const double> z) {
  if (written_ + z.size() > grid_.size())
    throw std::invalid_argument("height field: more values than the grid's " + std::to_string(grid_.size()) + " nodes");
  std::vector<std::uint32_t> buf(z.size());
  for (std::size_t k = 0; k < z.size(); ++k)
    buf[k] = to_little(std::bit_cast<std::uint32_t>(static_cast<float>(z[k])));
  out_.write(reinterpret_cast<const char*>(buf.data()), static_cast<std::streamsize>(buf.size() * 4));
  if (!out_) throw HeightFieldError(path_.string() + ": write error");
  written_ += z.size();
}

void HeightFieldWriter::finish() {
  if (written_ != grid_.size())
    throw std::invalid_argument("height field: " + std::to_string(written_) + " values for a grid of " +
                                std::to_string(grid_.size()) + " nodes");
  out_.close();
  if (!out_) throw HeightFieldError(path_.string() + ": write error");
  const auto side = height_field_sidecar(path_);
  std::ofstream t(side);
  if (!t) throw HeightFieldError(side.string() + ": cannot open for writing (" + std::generic_category().message(errno) + ")");
  t << kMagic << "\n"
    << "nx " << grid_.nx << "\nny " << grid_.ny << "\nx0 " << num(grid_.x0) << "\ny0 " << num(grid_.y0) << "\ndx "
    << num(grid_.dx) << "\ndy " << num(grid_.dy) << "\nnodata nan\n";
  if (work_offset_)  // + 0.0: no "-0"
    t << "work_offset_x " << num(work_offset_->x + 0.0) << "\nwork_offset_y " << num(work_offset_->y + 0.0) << "\nwork_offset_z "
      << num(work_offset_->z + 0.0) << "\n";
  if (work_origin_)
    t << "work_origin_x " << num(work_origin_->x + 0.0) << "\nwork_origin_y " << num(work_origin_->y + 0.0)
      << "\nwork_origin_z " << num(work_origin_->z + 0.0) << "\n";
  if (!t) throw HeightFieldError(side.string() + ": write error");
}

void write_height_field(const std::filesystem::path& data_path, const GridSpec& grid, std::span<const double> z,
                        std::optional<geometry::Vec3> work_offset, std::optional<geometry::Vec3> work_origin) {
  if (z.size() != grid.size())
    throw std::invalid_argument("height field: " + std::to_string(z.size()) + " values for a grid of " +
                                std::to_string(grid.size()) + " nodes");
  HeightFieldWriter w(data_path, grid, work_offset, work_origin);
  w.append(z);
  w.finish();
}

HeightFieldData read_height_field(const std::filesystem::path& data_path) {
  const auto side = height_field_sidecar(data_path);
  std::ifstream t(side);
  if (!t) throw HeightFieldError(side.string() + ": cannot open (" + std::generic_category().message(errno) + ")");
  std::string line;
  int line_no = 0;
  auto err = [&](const std::string& why) { return HeightFieldError(side.string() + ":" + std::to_string(line_no) + ": " + why); };
  ++line_no;
  if (!std::getline(t, line) || line != kMagic) throw err("expected '" + std::string(kMagic) + "'");
  std::map<std::string, double> v;
  while (std::getline(t, line)) {
    ++line_no;
    if (line.empty() || line[0] == '#') continue;
    const auto sp = line.find(' ');
    if (sp == std::string::npos) throw err("expected 'key value', got '" + line + "'");
    const std::string key = line.substr(0, sp), val = line.substr(sp + 1);
    if (key == "nodata") {
      if (val != "nan") throw err("only 'nodata nan' is supported");
      continue;
    }
    if (key != "nx" && key != "ny" && key != "x0" && key != "y0" && key != "dx" && key != "dy" &&
        key != "work_offset_x" && key != "work_offset_y" && key != "work_offset_z" && key != "work_origin_x" &&
        key != "work_origin_y" && key != "work_origin_z")
      throw err("unknown key '" + key + "'");
    double d = 0;
    const auto [p, ec] = std::from_chars(val.data(), val.data() + val.size(), d);
    if (ec != std::errc() || p != val.data() + val.size() || !std::isfinite(d))
      throw err("'" + val + "' is not a number");
    if (v.count(key)) throw err("'" + key + "' given twice");
    v[key] = d;
  }
  ++line_no;
  for (const char* key : {"nx", "ny", "x0", "y0", "dx", "dy"})
    if (!v.count(key)) throw err(std::string("missing '") + key + "'");
  HeightFieldData out;
  auto count = [&](const char* key) {
    const double d = v[key];
    if (!(d >= 1) || d != std::floor(d) || d > 1e8) throw err(std::string("'") + key + "' must be a positive integer");
    return static_cast<std::size_t>(d);
  };
  out.grid.nx = count("nx");
  out.grid.ny = count("ny");
  out.grid.x0 = v["x0"];
  out.grid.y0 = v["y0"];
  out.grid.dx = v["dx"];
  out.grid.dy = v["dy"];
  const int offsets = static_cast<int>(v.count("work_offset_x") + v.count("work_offset_y") + v.count("work_offset_z"));
  if (offsets == 3) {
    out.work_offset = geometry::Vec3{v["work_offset_x"], v["work_offset_y"], v["work_offset_z"]};
  } else if (offsets != 0) {
    throw err("work_offset_x, work_offset_y and work_offset_z go together");
  }
  const int origins = static_cast<int>(v.count("work_origin_x") + v.count("work_origin_y") + v.count("work_origin_z"));
  if (origins == 3) out.work_origin = geometry::Vec3{v["work_origin_x"], v["work_origin_y"], v["work_origin_z"]};
  else if (origins != 0) throw err("work_origin_x, work_origin_y and work_origin_z go together");
  if (!(out.grid.dx > 0) || !(out.grid.dy > 0)) throw err("dx and dy must be positive");
  if (out.grid.size() > (std::size_t{1} << 32)) throw err("grid is too large");

  std::ifstream f(data_path, std::ios::binary);
  if (!f) throw HeightFieldError(data_path.string() + ": cannot open (" + std::generic_category().message(errno) + ")");
  const std::uintmax_t want = out.grid.size() * 4;
  std::error_code ec;
  const std::uintmax_t have = std::filesystem::file_size(data_path, ec);
  if (ec || have != want)
    throw HeightFieldError(data_path.string() + ": expected " + std::to_string(want) + " bytes (" +
                           std::to_string(out.grid.nx) + " x " + std::to_string(out.grid.ny) + " float32), found " +
                           (ec ? ec.message() : std::to_string(have)));
  std::vector<std::uint32_t> buf(out.grid.size());
  f.read(reinterpret_cast<char*>(buf.data()), static_cast<std::streamsize>(want));
  if (!f) throw HeightFieldError(data_path.string() + ": read error");
  out.z.resize(buf.size());
  for (std::size_t k = 0; k < buf.size(); ++k) out.z[k] = std::bit_cast<float>(to_little(buf[k]));
  return out;
}

}  // namespace cncstream::cam
