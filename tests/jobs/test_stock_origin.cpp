// A stock carried from one job to the next keeps its place: the saved
// surface records the machine coordinates of the work zero it was saved in,
// and a second setup with its zero elsewhere reads it where it physically
// is (jobs/stock_spec.hpp), or is refused when its own zero is unknown.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <vector>

#include "cncstream/cam/height_field_io.hpp"
#include "cncstream/jobs/stock_spec.hpp"

using namespace cncstream;

namespace {

// The first job's work zero on the machine, and the second's (the block
// re-clamped: 7 mm further in X, 4 mm nearer in Y, its zero 1.5 mm higher).
const geometry::Vec3 kFirstOrigin{120, 80, -42}, kSecondOrigin{127, 76, -40.5};

// What the first job left, in its work coordinates: a block X 0..40, Y 0..30
// with its top at 0, the left half (X < 20) cut down to -3.
cam::HeightFieldData first_job_left() {
  cam::HeightFieldData d;
  d.grid = cam::GridSpec::covering(0, 0, 40, 30, 0.5, 0.5);
  d.z.resize(d.grid.size());
  for (std::size_t j = 0; j < d.grid.ny; ++j)
    for (std::size_t i = 0; i < d.grid.nx; ++i) d.z[j * d.grid.nx + i] = d.grid.x(i) < 20 ? -3.0f : 0.0f;
  return d;
}

// The physical surface at machine X,Y (machine Z), as the first job left it.
double machine_surface(double mx, double my) {
  const double wx = mx - kFirstOrigin.x;
  (void)my;
  return (wx < 20 ? -3.0 : 0.0) + kFirstOrigin.z;
}

struct SavedStock {
  std::filesystem::path map;
  SavedStock() {
    const auto dir = std::filesystem::temp_directory_path() / ("cncstream_stock_origin_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    map = dir / "left.f32";
    const cam::HeightFieldData d = first_job_left();
    cam::write_height_field(map, d.grid, std::vector<double>(d.z.begin(), d.z.end()), std::nullopt, kFirstOrigin);
  }
  ~SavedStock() { std::filesystem::remove_all(map.parent_path()); }
};

}  // namespace

TEST(StockOrigin, ASecondSetupReadsTheSavedSurfaceWhereItPhysicallyIs) {
  SavedStock saved;
  EXPECT_EQ(cam::read_height_field(saved.map).work_origin, kFirstOrigin);
  jobs::StockSpec spec = jobs::parse_stock_spec(saved.map.string());
  spec.work_origin = kSecondOrigin;
  // The second part sits well inside what is left, in its own work coordinates.
  const geometry::Box3 part{geometry::Vec3{5, 5, -10}, geometry::Vec3{25, 20, -4}};
  const jobs::WorkStock w = jobs::resolve_stock(spec, part);
  // At every point of the second job's work area, the stock's top it plans
  // with is the physical one: so it neither cuts air above the cut half nor
  // plunges into the uncut half.
  int checked = 0, would_err_unplaced = 0;
  // Where the saved map reaches (its Y 0 is this job's Y 4).
  for (double x = 0; x <= 30; x += 0.5)
    for (double y = 4; y <= 20; y += 0.5) {
      const double mx = x + kSecondOrigin.x, my = y + kSecondOrigin.y;
      // Leave the nodes beside the step (the nearest-node read may take either side).
      if (std::fabs(mx - kFirstOrigin.x - 20) < 0.6) continue;
      const double physical = machine_surface(mx, my) - kSecondOrigin.z;
      EXPECT_NEAR(w.top_at(x, y), physical, 1e-4) << x << "," << y;
      ++checked;
      // The old reading (the saved work coordinates taken as this job's).
      const cam::HeightFieldData raw = first_job_left();
      const std::size_t i = static_cast<std::size_t>(std::lround(x / 0.5)), j = static_cast<std::size_t>(std::lround(y / 0.5));
      if (std::fabs(raw.z[j * raw.grid.nx + i] - physical) > 0.5) ++would_err_unplaced;
    }
  EXPECT_GT(checked, 1500);
  // The negative control: read unplaced, a band 7 mm wide along the step is
  // wrong by 3 mm (uncut stock taken as cut: a plunge) and everywhere the 1.5
  // mm change of zero height (air or a deeper first pass).
  EXPECT_GT(would_err_unplaced, checked / 2);
  EXPECT_NEAR(w.box.hi.z, 0 + kFirstOrigin.z - kSecondOrigin.z, 1e-4);
  EXPECT_NEAR(w.box.lo.x, kFirstOrigin.x - kSecondOrigin.x, 1e-9);
}

TEST(StockOrigin, AnUnknownWorkZeroIsRefusedNamingTheSavedOne) {
  SavedStock saved;
  const jobs::StockSpec spec = jobs::parse_stock_spec(saved.map.string());
  const geometry::Box3 part{geometry::Vec3{5, 5, -10}, geometry::Vec3{25, 20, -4}};
  try {
    jobs::resolve_stock(spec, part);
    FAIL() << "accepted a saved stock without knowing this job's work zero";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("X120.000 Y80.000 Z-42.000"), std::string::npos) << what;
    EXPECT_NE(what.find("--work-origin"), std::string::npos) << what;
    EXPECT_NE(what.find(saved.map.string()), std::string::npos) << what;
  }
}

TEST(StockOrigin, TheSameZeroReadsTheSurfaceUnchangedAndAnOldFileAsBefore) {
  SavedStock saved;
  jobs::StockSpec spec = jobs::parse_stock_spec(saved.map.string());
  spec.work_origin = kFirstOrigin;
  const geometry::Box3 part{geometry::Vec3{5, 5, -10}, geometry::Vec3{35, 25, -4}};
  const jobs::WorkStock same = jobs::resolve_stock(spec, part);
  EXPECT_NEAR(same.top_at(10, 10), -3, 1e-6);
  EXPECT_NEAR(same.top_at(30, 10), 0, 1e-6);
  // A file without an origin (written before origins were recorded): its own work coordinates.
  const cam::HeightFieldData d = first_job_left();
  cam::write_height_field(saved.map, d.grid, std::vector<double>(d.z.begin(), d.z.end()));
  spec.work_origin = kSecondOrigin;
  EXPECT_NEAR(jobs::resolve_stock(spec, part).top_at(10, 10), -3, 1e-6);
}
