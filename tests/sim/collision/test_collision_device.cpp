// CPU vs CUDA agreement of the contact queries (label gpu): every test skips, naming the reason, on a
// machine without a CUDA device. The device runs the CPU's per-index kernels compiled without FMA
// contraction on both sides, with IEEE division and square root, and writes the records in the same
// (vertex, primitive) order: the contacts must be identical, byte for byte.
#include "collision_test_meshes.h"

#include "ctsurg/sim/base/backend.h"

#include <gtest/gtest.h>

#include <random>

namespace ctsurg::sim {
namespace {

using collision_test::expect_identical;
using collision_test::Scene;

class CollisionDeviceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!cuda_built()) GTEST_SKIP() << "this build has no CUDA (CTSURG_CUDA=OFF or no nvcc)";
    if (cuda_device_count() == 0) GTEST_SKIP() << "no CUDA device on this machine";
  }
};

TEST_F(CollisionDeviceTest, VertexTriangleContactsMatchTheCpu) {
  for (const int triangles : {0, 1, 500, 200000}) {
    const Scene s = collision_test::random_soup(triangles, 50000, 100, 1.5, {0, 0, 650}, 21 + triangles);
    for (const ContactPairs pairs : {ContactPairs::between_objects, ContactPairs::all}) {
      ContactOptions cpu, cuda;
      cpu.pairs = cuda.pairs = pairs;
      cuda.backend = Backend::cuda;
      const auto a = vertex_triangle_contacts(s.positions, s.primitives, s.vertex_object, s.primitive_object, 0.3, cpu);
      const auto b = vertex_triangle_contacts(s.positions, s.primitives, s.vertex_object, s.primitive_object, 0.3, cuda);
      if (triangles >= 500) {
        EXPECT_GT(a.size(), 0u);
      }
      expect_identical(b, a, "cuda vs cpu");
    }
  }
}

TEST_F(CollisionDeviceTest, VertexTetContactsMatchTheCpu) {
  Scene s = collision_test::tet_box({30, 20, 20}, {60, 40, 40}, {-30, -20, 630});
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.1, 1.1);
  for (int p = 0; p < 100000; ++p)
    collision_test::add_point(s, -30 + 60 * u(rng), -20 + 40 * u(rng), 630 + 40 * u(rng), 1);
  ContactOptions cpu, cuda;
  cuda.backend = Backend::cuda;
  const auto a = vertex_tet_contacts(s.positions, s.primitives, s.vertex_object, s.primitive_object, cpu);
  const auto b = vertex_tet_contacts(s.positions, s.primitives, s.vertex_object, s.primitive_object, cuda);
  EXPECT_GT(a.size(), 50000u);
  expect_identical(b, a, "cuda vs cpu");
}

}  // namespace
}  // namespace ctsurg::sim
