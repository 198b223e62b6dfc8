#pragma once
// STL reader: ASCII and binary. Binary is recognised by the size rule
// (84 + 50*n bytes), never by the word "solid". Stored normals are ignored.
#include <cstddef>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "cncstream/geometry/mesh.hpp"

namespace cncstream::geometry {

enum class LengthUnit { Millimetre, Inch, Metre };
LengthUnit parse_length_unit(const std::string& s);  // "mm" | "in" | "m"
double unit_to_mm(LengthUnit u);

struct StlLoadOptions {
  LengthUnit units = LengthUnit::Millimetre;
  double scale = 1.0;  // applied after the unit conversion
};

struct StlLoadResult {
  Mesh mesh;
  bool binary = false;
  std::size_t facets_read = 0;
  std::size_t dropped_degenerate = 0;
  std::string solid_name;
};

// Every error names the file and either the line (ASCII) or the byte offset
// (binary) where the problem is.
class StlError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

StlLoadResult load_stl(const std::filesystem::path& path, const StlLoadOptions& options = {});
// Parse from memory; `name` is used in error messages.
StlLoadResult parse_stl(const std::string& bytes, const std::string& name,
                        const StlLoadOptions& options = {});

// Writers (used by the simulator for machined results and by tests).
void write_stl_binary(const std::filesystem::path& path, const Mesh& mesh,
                      const std::string& header = "cncstream");

}  // namespace cncstream::geometry
