#include "ctsurg/sim/springs/sphere_tools.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/springs/spring_mass_step.h"
#include "ctsurg/sim/springs/stability.h"
#include "sim_test_models.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ctsurg::sim {
namespace {

using test::block_occupancy;
using test::test_material;

TEST(SphereTools, ProbePushesParticlesOutToTheSurface) {
  const auto model = build_spring_grid_model(block_occupancy(5, 5, 5, 2.0), test_material());
  auto s = model.make_state();
  const int32_t centre = model.particle_at(3, 3, 3);
  const Sphere tool{{s.x[centre] + 0.5, double(s.y[centre]), double(s.z[centre])}, 2.3};
  s.set_fixed(model.particle_at(3, 3, 4), true);  // inside the sphere but fixed: stays
  const int64_t moved = probe_sphere(s, tool);
  EXPECT_EQ(moved, 5);  // 6 particles within 2.3 mm of the centre (2 mm cells), one of them fixed
  int64_t on_surface = 0;
  for (int32_t i = 0; i < s.count(); ++i) {
    const double r = std::sqrt(std::pow(s.x[i] - tool.centre[0], 2) + std::pow(s.y[i] - tool.centre[1], 2) +
                               std::pow(s.z[i] - tool.centre[2], 2));
    if (i == model.particle_at(3, 3, 4)) {
      EXPECT_LT(r, tool.radius);
      continue;
    }
    EXPECT_GE(r, tool.radius - 1e-5);
    on_surface += std::abs(r - tool.radius) < 1e-5;
  }
  EXPECT_EQ(on_surface, moved);
  EXPECT_THROW(probe_sphere(s, {{0, 0, 0}, 0}), InputError);
}

TEST(SphereTools, GrabbedParticlesFollowTheToolAndPullTheirNeighbours) {
  const auto model = build_spring_grid_model(block_occupancy(4, 4, 6, 2.0), test_material(2000, 1000));
  auto s = model.make_state();
  for (int32_t i = 0; i < s.count(); ++i)
    if (model.rest_positions[3 * i + 2] < 33) s.set_fixed(i, true);  // bottom layer
  const int32_t top = model.particle_at(2, 2, 6);
  Sphere tool{{double(s.x[top]) + 1, double(s.y[top]) + 1, double(s.z[top])}, 1.6};
  const Grab grab = grab_particles_in_sphere(s, tool);
  ASSERT_EQ(grab.particles.size(), 4u);  // the 4 top particles around the point between them
  for (std::size_t g = 1; g < grab.particles.size(); ++g) EXPECT_LT(grab.particles[g - 1], grab.particles[g]);
  StepParameters p;
  p.dt = critical_time_step(model).dt;
  p.damping = 0.01;
  const int32_t below = model.particle_at(2, 2, 5);
  const Real below_z0 = s.z[below];
  for (int n = 0; n < 3000; ++n) {  // pull up 3 mm over 3000 steps
    tool.centre[2] += 1e-3;
    step(model, s, p);
    apply_grab(s, grab, tool.centre);
  }
  for (std::size_t g = 0; g < grab.particles.size(); ++g) {
    const int32_t q = grab.particles[g];
    EXPECT_FLOAT_EQ(s.z[q], static_cast<Real>(tool.centre[2]) + grab.offsets[3 * g + 2]);
  }
  EXPECT_GT(s.z[below] - below_z0, 1.0);  // the neighbour below followed through the springs
  EXPECT_THROW(grab_particles_in_sphere(s, {{0, 0, 0}, -1}), InputError);
}

}  // namespace
}  // namespace ctsurg::sim
