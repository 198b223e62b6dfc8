#include "cncstream/jobs/work_setup.hpp"

#include <cmath>

namespace cncstream::jobs {

WorkSetup work_setup(const geometry::Box3& part, XYOrigin xy, ZZero z, int decimals) {
  WorkSetup w;
  w.offset = work_offset(part, xy, z);
  w.lattice = cam::XYLattice{std::pow(10.0, -decimals), -w.offset.x, -w.offset.y, -w.offset.z};
  return w;
}

}  // namespace cncstream::jobs
