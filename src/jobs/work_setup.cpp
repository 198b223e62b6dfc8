#include "cncstream/jobs/work_setup.hpp"

#include <cmath>

namespace cncstream::jobs {

WorkSetup work_setup(const Box3& part, XYOrigin xy, ZZero z, int decimals) {
  WorkSetup w;
  w.offset = work_offset(part, xy, z);
  w.lattice = XYLattice{std::pow(10.0, -decimals), -w.offset.x, -w.offset.y};
  return w;
}

}  // namespace cncstream::jobs
