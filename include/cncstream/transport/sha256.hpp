#pragma once
// SHA-256 (FIPS 180-4) for identifying a G-code file in the journal: the same
// bytes give the same hash, so a restart can check it resumes the right file.
#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace cncstream::transport {

class Sha256 {
 public:
  Sha256();
  void update(std::string_view bytes);
  std::array<std::uint8_t, 32> finish();
  static std::string hex(const std::array<std::uint8_t, 32>& d);

 private:
  void block(const std::uint8_t* p);
  std::array<std::uint32_t, 8> h_;
  std::array<std::uint8_t, 64> buf_{};
  std::size_t buf_len_ = 0;
  std::uint64_t total_ = 0;
};

std::string sha256_hex(std::string_view bytes);
// Hashes a file in chunks; throws std::runtime_error naming the file.
std::string sha256_file(const std::filesystem::path& path);

}  // namespace cncstream::transport
