#include "cncstream/jobs/output_file.hpp"

#include <unistd.h>

#include <atomic>
#include <fstream>
#include <stdexcept>
#include <string>
#include <system_error>

namespace cncstream::jobs {

namespace fs = std::filesystem;

void write_file_atomically(const fs::path& path, const std::function<void(const fs::path& file)>& write) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (fs::exists(st) && !fs::is_regular_file(st)) {
    write(path);
    return;
  }
  // A name of its own: two jobs writing the same target (or a user's own
  // X.part) never share the temporary file.
  static std::atomic<unsigned long> serial{0};
  fs::path temporary = path;
  temporary += ".part-" + std::to_string(::getpid()) + "-" + std::to_string(++serial);
  try {
    write(temporary);
    fs::rename(temporary, path);
  } catch (...) {
    fs::remove(temporary, ec);
    throw;
  }
}

void write_text_file_atomically(const fs::path& path, std::string_view text) {
  write_file_atomically(path, [&](const fs::path& file) {
    std::ofstream f(file, std::ios::binary);
    if (!f) throw std::runtime_error(path.string() + ": cannot open for writing");
    f.write(text.data(), static_cast<std::streamsize>(text.size()));
    f.close();
    if (!f) throw std::runtime_error(path.string() + ": write failed");
  });
}

}  // namespace cncstream::jobs
