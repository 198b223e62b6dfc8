#include "cncstream/transport/port_discovery.hpp"

#include <fmt/core.h>

#include <libserialport.h>

#include <cctype>
#include <stdexcept>

namespace cncstream::transport {

const std::vector<KnownBoard>& known_boards() {
  static const std::vector<KnownBoard> boards = {
      {0x1A86, 0x7523, "CH340 USB-serial (Arduino Nano clones, many GRBL boards)"},
      {0x1A86, 0x55D4, "CH9102 USB-serial (ESP32 boards, FluidNC)"},
      {0x1A86, 0x7522, "CH340K USB-serial"},
      {0x0403, 0x6001, "FTDI FT232R (Arduino Duemilanove, GRBL shields)"},
      {0x0403, 0x6015, "FTDI FT231X"},
      {0x2341, std::nullopt, "Arduino (Uno/Mega, GRBL)"},
      {0x2A03, std::nullopt, "Arduino.org (GRBL)"},
      {0x10C4, 0xEA60, "Silicon Labs CP210x (ESP32 boards, FluidNC)"},
      {0x0483, 0x5740, "STM32 virtual COM port (grblHAL)"},
      {0x1209, 0x6070, "grblHAL (pid.codes)"},
      {0x2E8A, 0x000A, "Raspberry Pi RP2040 (grblHAL)"},
      {0x16C0, 0x0483, "Teensy (grblHAL iMXRT1062)"},
      {0x303A, std::nullopt, "Espressif native USB (ESP32-S2/S3, FluidNC)"},
      {0x1D50, 0x6029, "Marlin (OpenMoko VID)"},
      {0x1D50, 0x614E, "Marlin/Klipper (OpenMoko VID)"},
  };
  return boards;
}

std::string match_known_board(std::optional<std::uint16_t> vid, std::optional<std::uint16_t> pid) {
  if (!vid) return {};
  for (const auto& b : known_boards())
    if (b.vid == *vid && (!b.pid || (pid && *b.pid == *pid))) return b.name;
  return {};
}

std::string match_board_by_name(const PortInfo& p) {
  std::string text = p.product + " | " + p.manufacturer + " | " + p.description;
  for (char& ch : text) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  for (const char* word : {"grblhal", "grbl", "fluidnc", "marlin", "cnc"})
    if (text.find(word) != std::string::npos) return std::string("controller by name ('") + word + "' in its USB description)";
  return {};
}

std::vector<PortInfo> list_ports() {
  sp_port** ports = nullptr;
  if (sp_list_ports(&ports) != SP_OK) {
    char* msg = sp_last_error_message();
    std::string m = msg ? msg : "unknown error";
    sp_free_error_message(msg);
    throw std::runtime_error("cannot list serial ports: " + m);
  }
  std::vector<PortInfo> out;
  for (int i = 0; ports[i]; ++i) {
    sp_port* p = ports[i];
    PortInfo info;
    auto str = [](const char* s) { return s ? std::string(s) : std::string(); };
    info.path = str(sp_get_port_name(p));
    info.description = str(sp_get_port_description(p));
    switch (sp_get_port_transport(p)) {
      case SP_TRANSPORT_USB: {
        info.transport = "usb";
        int vid = 0, pid = 0;
        if (sp_get_port_usb_vid_pid(p, &vid, &pid) == SP_OK) {
          info.vid = static_cast<std::uint16_t>(vid);
          info.pid = static_cast<std::uint16_t>(pid);
        }
        info.manufacturer = str(sp_get_port_usb_manufacturer(p));
        info.product = str(sp_get_port_usb_product(p));
        info.serial = str(sp_get_port_usb_serial(p));
        break;
      }
      case SP_TRANSPORT_BLUETOOTH: info.transport = "bluetooth"; break;
      default: info.transport = "native"; break;
    }
    info.board = match_known_board(info.vid, info.pid);
    if (info.board.empty()) info.board = match_board_by_name(info);
    out.push_back(std::move(info));
  }
  sp_free_port_list(ports);
  return out;
}

std::string format_port(const PortInfo& p) {
  std::string s = p.path + "  [" + p.transport;
  if (p.vid && p.pid) {
    s += fmt::format(" {:04X}:{:04X}", *p.vid, *p.pid);
  }
  s += "]";
  if (!p.manufacturer.empty()) s += "  " + p.manufacturer;
  if (!p.product.empty()) s += " / " + p.product;
  if (!p.serial.empty()) s += "  serial " + p.serial;
  if (!p.board.empty()) s += "  -> " + p.board;
  else if (!p.description.empty()) s += "  (" + p.description + ")";
  return s;
}

AutoChoice choose_auto_port(const std::vector<PortInfo>& ports) {
  std::vector<const PortInfo*> known;
  for (const auto& p : ports)
    if (!p.board.empty()) known.push_back(&p);
  AutoChoice c;
  if (known.size() == 1) {
    c.port = *known.front();
    c.message = "using " + format_port(*known.front());
    return c;
  }
  if (known.empty()) {
    c.message = "no serial port with a known controller USB ID or name was found";
    if (!ports.empty()) {
      c.message += "; ports present:";
      for (const auto& p : ports) c.message += "\n  " + format_port(p);
      c.message += "\nname the port explicitly (e.g. /dev/ttyUSB0)";
    }
    return c;
  }
  c.message = std::to_string(known.size()) + " controller-like ports found; name one explicitly:";
  for (const auto* p : known) c.message += "\n  " + format_port(*p);
  return c;
}

}  // namespace cncstream::transport
