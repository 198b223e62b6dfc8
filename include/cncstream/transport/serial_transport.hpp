#pragma once
// Serial transport over Boost.Asio: works on real ports and pseudo-terminals.
// Reads are continuous and asynchronous; a read error or end of file (USB
// unplugged, EIO) is reported once through the close handler at once.
// Opening a port takes it exclusively (port_lock.hpp: a lock file and
// TIOCEXCL); closing it, or the end of the process, gives it back.
#include <boost/asio/io_context.hpp>
#include <boost/asio/serial_port.hpp>

#include <array>
#include <deque>
#include <functional>
#include <string>
#include <string_view>

#include "cncstream/transport/port_lock.hpp"

namespace cncstream::transport {

struct SerialSettings {
  unsigned baud = 115200;
  unsigned data_bits = 8;
  char parity = 'N';      // 'N', 'E', 'O'
  unsigned stop_bits = 1; // 1 or 2
  bool rtscts = false;
  // Drop DTR briefly after opening so Arduino-style boards reset and print
  // their banner even if the port was already open elsewhere (HUPCL off).
  bool pulse_dtr = false;
};
// "115200", "115200,8N1", "250000,8E2"; throws std::invalid_argument naming the spec.
SerialSettings parse_serial_settings(const std::string& spec);

class SerialTransport {
 public:
  using DataHandler = std::function<void(std::string_view)>;
  using CloseHandler = std::function<void(const std::string& reason)>;

  SerialTransport(boost::asio::io_context& io, SerialSettings settings);
  ~SerialTransport();

  // Takes the port (lock file, then TIOCEXCL), opens and configures it;
  // throws PortBusyError naming the owner when another process has it,
  // std::runtime_error naming the path for anything else.
  void open(const std::string& path);
  // Starts reading: `on_data` for every chunk, `on_close` once on EOF/error.
  void start(DataHandler on_data, CloseHandler on_close);
  // Queues bytes; writes happen in order.
  void write(std::string bytes);
  void close();
  // Closes once every queued byte has been written (a final reset byte must
  // reach the controller before the port goes away).
  void close_when_flushed();
  bool is_open() const { return port_.is_open(); }
  const std::string& path() const { return path_; }
  std::size_t bytes_written() const { return bytes_written_; }
  std::size_t bytes_read() const { return bytes_read_; }
  // What the operator should know about taking the port (a stale lock
  // removed, a fallback lock folder); empty when nothing.
  const std::string& lock_note() const { return lock_note_; }
  const PortLock& lock() const { return lock_; }

 private:
  void read_some();
  void write_next();
  void closed(const std::string& reason);
  void shut();  // gives the port back: TIOCNXCL, close, lock file

  boost::asio::serial_port port_;
  SerialSettings settings_;
  std::string path_;
  PortLock lock_;
  std::string lock_note_;
  DataHandler on_data_;
  CloseHandler on_close_;
  std::array<char, 4096> buf_{};
  std::deque<std::string> queue_;
  bool writing_ = false;
  bool close_reported_ = false;
  bool close_pending_ = false;
  std::size_t bytes_written_ = 0, bytes_read_ = 0;
};

}  // namespace cncstream::transport
