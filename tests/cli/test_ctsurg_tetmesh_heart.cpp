// ctsurg-tetmesh on real data: the bundled heart (data_samples/heart) through ctsurg-import,
// ctsurg-grid and ctsurg-tetmesh, as the demo runs it (label realdata: tens of seconds).
#include "ctsurg/core/tet_mesh_file.h"
#include "test_support.h"

#include <gtest/gtest.h>

namespace fs = std::filesystem;
using ctsurg::test::run_tool;
using ctsurg::test::TempDir;

namespace {

// The bundled heart (data_samples/heart) at the demo's 2.4 mm cell size, coarsened to keep the test
// short: a valid mesh without slivers whose volume is within 3 % of the mask's.
TEST(CtsurgTetmeshRealdata, BundledHeart) {
  const fs::path heart = ctsurg::test::source_dir() / "data_samples" / "heart";
  if (!fs::exists(heart / "heart_ct.nii.gz")) GTEST_SKIP() << "bundled heart absent";
  TempDir dir;
  auto r = run_tool("ctsurg-import", {(heart / "heart_ct.nii.gz").string(), (dir / "ct.h5").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run_tool("ctsurg-grid", {(dir / "ct.h5").string(), (heart / "heart_mask.nii.gz").string(), (dir / "grid.h5").string(),
                               "--voxel-mm", "2.4", "--no-preview"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run_tool("ctsurg-tetmesh", {(dir / "grid.h5").string(), (dir / "heart.h5").string(), "--cell-size", "4"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto m = ctsurg::read_tet_mesh_file(dir / "heart.h5");
  EXPECT_GT(m.tet_count(), 10000);
  EXPECT_EQ(m.quality.inverted, 0);
  EXPECT_EQ(m.quality.slivers, 0) << "min dihedral " << m.quality.min_dihedral_deg;
  EXPECT_NEAR(m.quality.volume_mm3, m.mask_volume_mm3, 0.03 * m.mask_volume_mm3);
}

}  // namespace
