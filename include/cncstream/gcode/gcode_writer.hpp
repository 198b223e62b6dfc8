#pragma once
// Writes GRBL-safe G-code: plain decimals (never exponent notation), modal
// words only when they change, lines of at most `max_line` characters, no
// words GRBL rejects. The writer only formats; callers decide the moves.
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace cncstream {

// Plain decimal with at most `decimals` digits after the point, trailing
// zeros trimmed, "-0" printed as "0".
std::string format_gcode_number(double value, int decimals = 3);

class GcodeWriter {
 public:
  explicit GcodeWriter(int decimals = 3, std::size_t max_line = 80);

  // "(text)": parentheses and non-printable characters are replaced; long
  // text is wrapped over several comment lines.
  void comment(const std::string& text);
  // A line of words written as given (validated for length and characters).
  void line(const std::string& text);
  // G0 / G1 with only the axes and feed that change. Returns false (and
  // writes nothing) if the move is a zero-length repeat.
  bool rapid(std::optional<double> x, std::optional<double> y, std::optional<double> z);
  bool feed(std::optional<double> x, std::optional<double> y, std::optional<double> z, double feed_rate);
  // G2 (clockwise) / G3 in `plane` (G17/G18/G19, written when it changes)
  // to (x, y, z) with the centre at `center_offset` from the current point:
  // its two in-plane components are written (I/J/K) with `offset_decimals`.
  // Returns false (and writes nothing) if the end is the current point.
  bool arc(int plane, bool clockwise, double x, double y, double z, double i, double j, double k,
           double feed_rate, int offset_decimals = 4);

  // `plane`: 17, 18 or 19.
  // Forget the modal state (after something the writer did not see).
  void reset_modal();

  const std::vector<std::string>& lines() const { return lines_; }
  std::string text() const;
  std::size_t motion_lines() const { return motion_lines_; }

 private:
  bool move(int g, std::optional<double> x, std::optional<double> y, std::optional<double> z,
            std::optional<double> f, const std::string& prefix = {}, const std::string& offsets = {});

  int decimals_;
  std::size_t max_line_;
  std::vector<std::string> lines_;
  std::optional<int> motion_;
  int plane_ = 17;  // G17 until an arc names another
  std::optional<std::string> x_, y_, z_, f_;  // last written values, as formatted
  std::size_t motion_lines_ = 0;
};

}  // namespace cncstream
