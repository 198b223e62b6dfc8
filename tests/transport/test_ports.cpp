#include <gtest/gtest.h>

#include "cncstream/transport/port_discovery.hpp"
#include "cncstream/transport/serial_transport.hpp"

using namespace cncstream::transport;

namespace {
PortInfo usb(const char* path, std::uint16_t vid, std::uint16_t pid) {
  PortInfo p;
  p.path = path;
  p.transport = "usb";
  p.vid = vid;
  p.pid = pid;
  p.board = match_known_board(vid, pid);
  return p;
}
}  // namespace

TEST(Ports, KnownBoards) {
  EXPECT_FALSE(match_known_board(0x1A86, 0x7523).empty());
  EXPECT_FALSE(match_known_board(0x0403, 0x6001).empty());
  EXPECT_FALSE(match_known_board(0x2341, 0x0043).empty());  // any Arduino product
  EXPECT_FALSE(match_known_board(0x10C4, 0xEA60).empty());
  EXPECT_NE(match_known_board(0x0483, 0x5740).find("grblHAL"), std::string::npos);
  EXPECT_TRUE(match_known_board(0x046D, 0xC077).empty());  // a mouse
  EXPECT_TRUE(match_known_board(std::nullopt, std::nullopt).empty());
}

TEST(Ports, AutoPicksTheOnlyKnownBoard) {
  PortInfo native;
  native.path = "/dev/ttyS0";
  native.transport = "native";
  auto c = choose_auto_port({native, usb("/dev/ttyUSB0", 0x1A86, 0x7523), usb("/dev/ttyACM0", 0x046D, 0xC077)});
  ASSERT_TRUE(c.port);
  EXPECT_EQ(c.port->path, "/dev/ttyUSB0");
  c = choose_auto_port({usb("/dev/ttyUSB0", 0x1A86, 0x7523), usb("/dev/ttyACM0", 0x0483, 0x5740)});
  EXPECT_FALSE(c.port);
  EXPECT_NE(c.message.find("/dev/ttyUSB0"), std::string::npos);
  EXPECT_NE(c.message.find("/dev/ttyACM0"), std::string::npos);
  c = choose_auto_port({native});
  EXPECT_FALSE(c.port);
  EXPECT_NE(c.message.find("/dev/ttyS0"), std::string::npos);
}

TEST(Ports, BoardsNamedInTheirDescriptionCount) {
  PortInfo p;
  p.path = "/dev/ttyACM0";
  p.transport = "usb";
  p.vid = 0x1234;
  p.pid = 0x5678;
  p.product = "GrblHAL CNC Controller";
  EXPECT_NE(match_board_by_name(p).find("grblhal"), std::string::npos);
  p.product = "USB Keyboard";
  EXPECT_TRUE(match_board_by_name(p).empty());
  p.description = "FluidNC ESP32-S3";
  EXPECT_NE(match_board_by_name(p).find("fluidnc"), std::string::npos);
  PortInfo mouse = usb("/dev/ttyUSB1", 0x046D, 0xC077);
  p.board = match_board_by_name(p);
  const auto c = choose_auto_port({mouse, p});
  ASSERT_TRUE(c.port);
  EXPECT_EQ(c.port->path, "/dev/ttyACM0");
}

TEST(Ports, ListingDoesNotThrow) { EXPECT_NO_THROW(list_ports()); }

TEST(SerialSettings, Parse) {
  auto s = parse_serial_settings("250000,8E2");
  EXPECT_EQ(s.baud, 250000u);
  EXPECT_EQ(s.parity, 'E');
  EXPECT_EQ(s.stop_bits, 2u);
  EXPECT_EQ(parse_serial_settings("115200").data_bits, 8u);
  EXPECT_THROW(parse_serial_settings("fast"), std::invalid_argument);
  EXPECT_THROW(parse_serial_settings("115200,9N1"), std::invalid_argument);
}
