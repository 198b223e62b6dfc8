#pragma once
// SHA-256 for identifying a file (the journal's G-code, the daemon's uploads):
// the same bytes give the same hash, so a restart can check it resumes the
// right file. Computed by nettle; its context stays out of this header.
#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

namespace cncstream::transport {

class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(Sha256&&) noexcept;
  Sha256& operator=(Sha256&&) noexcept;
  void update(std::string_view bytes);
  std::array<std::uint8_t, 32> finish();  // and starts over
  static std::string hex(const std::array<std::uint8_t, 32>& d);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

std::string sha256_hex(std::string_view bytes);
// Hashes a file in chunks; throws std::runtime_error naming the file.
std::string sha256_file(const std::filesystem::path& path);

}  // namespace cncstream::transport
