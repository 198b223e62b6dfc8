#pragma once
// Serial port discovery (libserialport) and the `auto` choice: the one port
// whose USB VID:PID belongs to a known controller board.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace cncstream::transport {

struct PortInfo {
  std::string path;          // /dev/ttyUSB0
  std::string description;
  std::string transport;     // "usb", "native", "bluetooth"
  std::optional<std::uint16_t> vid, pid;
  std::string manufacturer, product, serial;
  std::string board;         // what the VID:PID suggests, empty if not a known board
};

struct KnownBoard {
  std::uint16_t vid;
  std::optional<std::uint16_t> pid;  // nullopt: any product of this vendor
  const char* name;
};
const std::vector<KnownBoard>& known_boards();
// The board name for a VID:PID, or empty.
std::string match_known_board(std::optional<std::uint16_t> vid, std::optional<std::uint16_t> pid);
// A port whose USB IDs are unknown (a new board, a native USB firmware) may
// still name itself: "grbl", "fluidnc", "marlin", "cnc" in its product,
// manufacturer or description (case-insensitive). Empty if none.
std::string match_board_by_name(const PortInfo& port);

std::vector<PortInfo> list_ports();  // throws std::runtime_error if enumeration fails

struct AutoChoice {
  std::optional<PortInfo> port;  // set when exactly one known board was found
  std::string message;           // why not, listing the candidates
};
// Pure: picks among `ports` (testable without hardware).
AutoChoice choose_auto_port(const std::vector<PortInfo>& ports);

std::string format_port(const PortInfo& p);

}  // namespace cncstream::transport
