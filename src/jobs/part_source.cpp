#include "cncstream/jobs/part_source.hpp"

#include "cncstream/jobs/size_limits.hpp"

namespace cncstream::jobs {

std::shared_ptr<const geometry::Mesh> load_part(const PartSource& part) {
  std::shared_ptr<const geometry::Mesh> mesh = part.mesh;
  if (!mesh) {
    geometry::StlLoadOptions opt;
    opt.units = part.units;
    opt.scale = part.scale;
    mesh = std::make_shared<const geometry::Mesh>(geometry::load_stl(part.stl, opt).mesh);
  }
  if (mesh->triangles.empty())
    throw geometry::StlError(part.stl + ": the file holds no facets with area; nothing to machine");
  check_part_size(mesh->bounds(), part.stl.empty() ? std::string("the part") : part.stl, part.max_extent_mm);
  return mesh;
}

}  // namespace cncstream::jobs
