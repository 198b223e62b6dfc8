#include "cncstream/gcode/gcode_writer.hpp"

#include <fmt/core.h>

#include <cmath>
#include <stdexcept>

namespace cncstream {

std::string format_gcode_number(double value, int decimals) {
  if (!std::isfinite(value)) throw std::invalid_argument("G-code number is not finite");
  if (decimals < 0 || decimals > 6) throw std::invalid_argument("G-code decimals must be 0..6");
  if (std::fabs(value) >= 1e9) throw std::invalid_argument("G-code number too large: " + std::to_string(value));
  std::string s = fmt::format("{:.{}f}", value, decimals);
  if (s.find('.') != std::string::npos) {
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  return s;
}

namespace {
// Appends instead of "(" + s: GCC 12 warns falsely (-Wrestrict) on the latter.
std::string parenthesized(const std::string& s) {
  std::string out;
  out.reserve(s.size() + 2);
  out.push_back('(');
  out.append(s);
  out.push_back(')');
  return out;
}
}  // namespace

GcodeWriter::GcodeWriter(int decimals, std::size_t max_line) : decimals_(decimals), max_line_(max_line) {}

void GcodeWriter::comment(const std::string& text) {
  std::string clean;
  for (char c : text) {
    if (c == '(' ) c = '[';
    else if (c == ')') c = ']';
    else if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = ' ';
    clean += c;
  }
  const std::size_t width = max_line_ - 2;
  while (clean.size() > width) {
    std::size_t cut = clean.rfind(' ', width);
    const bool at_space = cut != std::string::npos && cut > 0;  // a space just past the width counts too
    if (!at_space) cut = width;
    lines_.push_back(parenthesized(clean.substr(0, cut)));
    clean = clean.substr(at_space ? cut + 1 : cut);
  }
  lines_.push_back(parenthesized(clean));
}

void GcodeWriter::line(const std::string& text) {
  if (text.size() > max_line_)
    throw std::invalid_argument("G-code line longer than " + std::to_string(max_line_) + " characters: " + text);
  for (char c : text)
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126)
      throw std::invalid_argument("G-code line has a non-printable character: " + text);
  lines_.push_back(text);
}

void GcodeWriter::reset_modal() {
  motion_.reset();
  plane_ = 0;
  x_.reset();
  y_.reset();
  z_.reset();
  f_.reset();
}

bool GcodeWriter::rapid(std::optional<double> x, std::optional<double> y, std::optional<double> z) {
  return move(0, x, y, z, std::nullopt);
}

bool GcodeWriter::feed(std::optional<double> x, std::optional<double> y, std::optional<double> z,
                       double feed_rate) {
  if (!(feed_rate > 0)) throw std::invalid_argument("feed rate must be positive");
  return move(1, x, y, z, feed_rate);
}

bool GcodeWriter::arc(int plane, bool clockwise, double x, double y, double z, double i, double j, double k,
                      double feed_rate, int offset_decimals) {
  if (plane < 17 || plane > 19) throw std::invalid_argument("arc plane must be 17, 18 or 19");
  if (!(feed_rate > 0)) throw std::invalid_argument("feed rate must be positive");
  // The two offsets in the plane (GRBL wants at least one; both are written).
  std::string offsets;
  auto offset = [&](char letter, double v) {
    offsets += letter;
    offsets += format_gcode_number(v, offset_decimals);
  };
  if (plane == 17) { offset('I', i); offset('J', j); }
  if (plane == 18) { offset('I', i); offset('K', k); }
  if (plane == 19) { offset('J', j); offset('K', k); }
  std::string prefix;
  if (plane != plane_) {
    prefix.append("G").append(std::to_string(plane));
  }
  const bool written = move(clockwise ? 2 : 3, x, y, z, feed_rate, prefix, offsets);
  if (written) plane_ = plane;
  return written;
}

bool GcodeWriter::move(int g, std::optional<double> x, std::optional<double> y, std::optional<double> z,
                       std::optional<double> f, const std::string& prefix, const std::string& offsets) {
  std::string words;
  auto axis = [&](char letter, std::optional<double> v, std::optional<std::string>& last) {
    if (!v) return;
    std::string s = format_gcode_number(*v, decimals_);
    if (last && *last == s) return;
    words += letter;
    words += s;
    last = std::move(s);
  };
  axis('X', x, x_);
  axis('Y', y, y_);
  axis('Z', z, z_);
  if (words.empty()) return false;
  words += offsets;
  // Built by appending: GCC 12 warns falsely (-Wrestrict) on prefix + words.
  std::string text;
  text.reserve(48);
  text.append(prefix);
  if (!motion_ || *motion_ != g) {
    text.append("G").append(std::to_string(g));
    motion_ = g;
  }
  if (f) {
    std::string s = format_gcode_number(*f, 1);
    if (!f_ || *f_ != s) {
      words += "F" + s;
      f_ = std::move(s);
    }
  }
  text.append(words);
  line(text);
  ++motion_lines_;
  return true;
}

std::string GcodeWriter::text() const {
  std::string out;
  for (const auto& l : lines_) {
    out += l;
    out += '\n';
  }
  return out;
}

}  // namespace cncstream
