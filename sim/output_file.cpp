#include "cncsim/output_file.hpp"

#include <unistd.h>

#include <atomic>
#include <string>
#include <system_error>

namespace cncsim {

void write_whole(const std::filesystem::path& path, const std::function<void(const std::filesystem::path& file)>& write) {
  static std::atomic<unsigned long> serial{0};
  std::filesystem::path temporary = path;
  temporary += ".part-" + std::to_string(::getpid()) + "-" + std::to_string(++serial);
  try {
    write(temporary);
    std::filesystem::rename(temporary, path);
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove(temporary, ec);
    throw;
  }
}

}  // namespace cncsim
