#include "cncstream/transport/serial_transport.hpp"

#include <boost/asio/read.hpp>
#include <boost/asio/write.hpp>

#include <sys/ioctl.h>
#include <termios.h>

#include <cerrno>
#include <charconv>
#include <cstring>
#include <stdexcept>
#include <system_error>
#include <thread>

namespace cncstream::transport {

SerialSettings parse_serial_settings(const std::string& spec) {
  SerialSettings s;
  const auto comma = spec.find(',');
  const std::string baud = spec.substr(0, comma);
  unsigned b = 0;
  const auto r = std::from_chars(baud.data(), baud.data() + baud.size(), b);
  if (r.ec != std::errc{} || r.ptr != baud.data() + baud.size() || b < 300 || b > 4000000)
    throw std::invalid_argument("serial settings '" + spec + "': baud rate must be a number within 300..4000000");
  s.baud = b;
  if (comma != std::string::npos) {
    const std::string f = spec.substr(comma + 1);
    if (f.size() != 3 || f[0] < '5' || f[0] > '8' || (f[1] != 'N' && f[1] != 'E' && f[1] != 'O') ||
        (f[2] != '1' && f[2] != '2'))
      throw std::invalid_argument("serial settings '" + spec + "': frame must look like 8N1 (bits 5-8, N/E/O, stop 1/2)");
    s.data_bits = static_cast<unsigned>(f[0] - '0');
    s.parity = f[1];
    s.stop_bits = static_cast<unsigned>(f[2] - '0');
  }
  return s;
}

SerialTransport::SerialTransport(boost::asio::io_context& io, SerialSettings settings)
    : port_(io), settings_(settings) {}

SerialTransport::~SerialTransport() { shut(); }

void SerialTransport::shut() {
  // TIOCEXCL stays on a tty that another process still holds open (the
  // simulator's pty keeps its slave open): clear it before closing, or the
  // next open of that pty by a non-root user fails with EBUSY.
  if (port_.is_open()) ::ioctl(port_.native_handle(), TIOCNXCL);
  boost::system::error_code ignored;
  port_.close(ignored);
  lock_.release();
}

void SerialTransport::open(const std::string& path) {
  path_ = path;
  lock_ = PortLock::acquire(path);  // throws PortBusyError naming the owner
  lock_note_ = lock_.note();
  boost::system::error_code ec;
  port_.open(path, ec);
  if (ec) {
    lock_.release();
    if (ec == boost::system::errc::device_or_resource_busy) {
      // TIOCEXCL of a program that takes no lock file: name whoever has it
      // open, as far as /proc lets this user see.
      const auto users = processes_using(path);
      std::string m = "cannot open " + path + ": it is in use by another process (TIOCEXCL)";
      if (!users.empty()) {
        m += "; open in";
        for (std::size_t i = 0; i < users.size(); ++i) m.append(i ? ", " : " ").append(users[i].describe());
      }
      PortOwner owner = users.empty() ? PortOwner{} : users.front();
      owner.device = resolve_device(path);
      throw PortBusyError(m, owner);
    }
    throw std::runtime_error(path + ": cannot open serial port: " + ec.message());
  }
  // Refuse every later open() of this tty, by programs that ignore lock files
  // too (root excepted: the kernel lets CAP_SYS_ADMIN through).
  if (::ioctl(port_.native_handle(), TIOCEXCL) != 0)
    lock_note_ += std::string(lock_note_.empty() ? "" : "; ") + path + ": no exclusive mode (TIOCEXCL): " +
                  std::generic_category().message(errno);
  using sp = boost::asio::serial_port_base;
  auto set = [&](const auto& opt, const char* what) {
    port_.set_option(opt, ec);
    if (ec) {
      shut();
      throw std::runtime_error(path + ": cannot set " + what + ": " + ec.message());
    }
  };
  set(sp::baud_rate(settings_.baud), "baud rate");
  set(sp::character_size(settings_.data_bits), "data bits");
  set(sp::parity(settings_.parity == 'E'   ? sp::parity::even
                 : settings_.parity == 'O' ? sp::parity::odd
                                           : sp::parity::none),
      "parity");
  set(sp::stop_bits(settings_.stop_bits == 2 ? sp::stop_bits::two : sp::stop_bits::one), "stop bits");
  set(sp::flow_control(settings_.rtscts ? sp::flow_control::hardware : sp::flow_control::none), "flow control");
  if (settings_.pulse_dtr) {
    // Pseudo-terminals have no modem lines: ignore the failure there.
    const int fd = port_.native_handle();
    int dtr = TIOCM_DTR;
    if (::ioctl(fd, TIOCMBIC, &dtr) == 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      ::ioctl(fd, TIOCMBIS, &dtr);
    }
  }
  // Drop whatever the OS buffered before we opened (old answers).
  ::tcflush(port_.native_handle(), TCIOFLUSH);
}

void SerialTransport::start(DataHandler on_data, CloseHandler on_close) {
  on_data_ = std::move(on_data);
  on_close_ = std::move(on_close);
  read_some();
}

void SerialTransport::read_some() {
  port_.async_read_some(boost::asio::buffer(buf_), [this](const boost::system::error_code& ec, std::size_t n) {
    if (n > 0) {
      bytes_read_ += n;
      if (on_data_) on_data_(std::string_view(buf_.data(), n));
    }
    if (ec || !port_.is_open()) {
      if (!ec || ec == boost::asio::error::operation_aborted) return;
      closed(ec == boost::asio::error::eof ? "end of file (device closed or unplugged)" : ec.message());
      return;
    }
    read_some();
  });
}

void SerialTransport::write(std::string bytes) {
  if (bytes.empty() || !port_.is_open()) return;
  queue_.push_back(std::move(bytes));
  if (!writing_) write_next();
}

void SerialTransport::write_next() {
  if (queue_.empty()) {
    writing_ = false;
    if (close_pending_) close();
    return;
  }
  writing_ = true;
  boost::asio::async_write(port_, boost::asio::buffer(queue_.front()),
                           [this](const boost::system::error_code& ec, std::size_t n) {
                             bytes_written_ += n;
                             queue_.pop_front();
                             if (ec) {
                               writing_ = false;
                               if (ec != boost::asio::error::operation_aborted) closed("write failed: " + ec.message());
                               return;
                             }
                             write_next();
                           });
}

void SerialTransport::closed(const std::string& reason) {
  shut();
  if (close_reported_) return;
  close_reported_ = true;
  if (on_close_) on_close_(reason);
}

void SerialTransport::close_when_flushed() {
  if (writing_) close_pending_ = true;
  else close();
}

void SerialTransport::close() {
  close_reported_ = true;  // a deliberate close is not a disconnect
  shut();
}

}  // namespace cncstream::transport
