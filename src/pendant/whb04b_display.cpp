#include "cncstream/pendant/whb04b_display.hpp"

#include <algorithm>
#include <cmath>

namespace cncstream::pendant {

namespace {

void put_u16(std::uint8_t* at, unsigned v) {
  at[0] = static_cast<std::uint8_t>(v & 0xFF);
  at[1] = static_cast<std::uint8_t>((v >> 8) & 0xFF);
}

}  // namespace

std::array<std::uint8_t, 4> encode_coordinate(double mm) {
  std::array<std::uint8_t, 4> out{};
  if (!std::isfinite(mm)) mm = 0;  // a display must never show garbage: 0 rather than a wrapped number
  constexpr double kMaxTenThousandths = 65535.0 * 10000.0 + 9999.0;
  const double scaled = std::min(std::round(std::fabs(mm) * 10000.0), kMaxTenThousandths);
  const auto ten_thousandths = static_cast<std::uint32_t>(scaled);
  const unsigned integer = ten_thousandths / 10000;
  unsigned fraction = ten_thousandths % 10000;
  if (mm < 0 && ten_thousandths > 0) fraction |= 0x8000;
  put_u16(out.data(), integer);
  put_u16(out.data() + 2, fraction);
  return out;
}

DisplayPayload encode_display(const DisplayState& s) {
  DisplayPayload p{};
  p[0] = 0xFE;  // header 0xfdfe, little-endian
  p[1] = 0xFD;
  p[2] = 0xFE;  // seed: the value LinuxCNC sends; its meaning is unknown
  std::uint8_t flags = static_cast<std::uint8_t>(s.mode) & 0x03;
  if (s.reset) flags |= 0x40;
  if (s.work_coordinates) flags |= 0x80;
  p[3] = flags;
  for (std::size_t i = 0; i < 3; ++i) {
    const auto c = encode_coordinate(s.coordinates[i]);
    std::copy(c.begin(), c.end(), p.begin() + 4 + 4 * static_cast<std::ptrdiff_t>(i));
  }
  put_u16(p.data() + 16, std::min(s.feed, 65535u));
  put_u16(p.data() + 18, std::min(s.spindle, 65535u));
  p[20] = 0;
  return p;
}

DisplayReports split_into_reports(const DisplayPayload& p) {
  DisplayReports r{};
  for (std::size_t i = 0; i < 3; ++i) {
    r[i][0] = 0x06;  // feature report id
    std::copy_n(p.begin() + static_cast<std::ptrdiff_t>(7 * i), 7, r[i].begin() + 1);
  }
  return r;
}

}  // namespace cncstream::pendant
