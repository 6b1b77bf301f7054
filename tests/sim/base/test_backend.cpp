#include "ctsurg/sim/base/backend.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/fem/fem_box_mesh.h"
#include "ctsurg/sim/fem/fem_explicit_dynamics.h"
#include "ctsurg/sim/fem/fem_static_solver.h"
#include "ctsurg/sim/springs/device_simulation.h"
#include "sim_test_models.h"

#include <gtest/gtest.h>

#include <string>

namespace ctsurg::sim {
namespace {

// The InputError `call` throws; fails the test when it throws nothing.
template <class Call>
InputError input_error(const Call& call) {
  try {
    call();
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no InputError thrown";
  return InputError("", "", "");
}

TEST(Backend, CpuIsAlwaysAvailableAndResolves) {
  EXPECT_TRUE(backend_available(Backend::cpu));
  EXPECT_EQ(resolve_backend("cpu"), Backend::cpu);
  EXPECT_NO_THROW(require_backend(Backend::cpu, "test"));
  EXPECT_STREQ(backend_name(Backend::cpu), "cpu");
  EXPECT_STREQ(backend_name(Backend::cuda), "cuda");
}

TEST(Backend, UnknownNameIsAnInputErrorNamingTheChoices) {
  const InputError e = input_error([] { resolve_backend("gpu", "scene.yaml"); });
  EXPECT_EQ(e.file(), "scene.yaml");
  EXPECT_EQ(e.field(), "backend");
  EXPECT_NE(e.problem().find("cpu, cuda or auto"), std::string::npos) << e.problem();
}

TEST(Backend, AutoPicksCudaExactlyWhenADeviceIsThere) {
  EXPECT_EQ(resolve_backend("auto"), backend_available(Backend::cuda) ? Backend::cuda : Backend::cpu);
  EXPECT_EQ(backend_available(Backend::cuda), cuda_built() && cuda_device_count() > 0);
  if (!cuda_built()) {
    EXPECT_EQ(cuda_device_count(), 0);
  }
}

// A machine without a device (this CI): cuda is refused with a message that says why and what to use;
// auto resolves to cpu. The FEM's device classes (FemExplicitDynamics' state, the static solver's CG)
// refuse the same way, before any work.
TEST(Backend, WithoutADeviceCudaIsRefusedClearly) {
  if (backend_available(Backend::cuda)) GTEST_SKIP() << "a CUDA device is present; this test is for machines without one";
  EXPECT_EQ(resolve_backend("auto"), Backend::cpu);
  const std::string why = cuda_built() ? "no CUDA device was found" : "this build has no CUDA";
  const auto box = fem_box_mesh({2, 2, 2}, {4, 4, 4});
  const FemModel fem = build_fem_model(box.nodes, box.tets, FemMaterial{});
  FemBoundaryConditions bc;
  for (int32_t i = 0; i < fem.node_count(); ++i)
    if (fem.nodes[3 * i + 2] == 0) bc.fixed_nodes.push_back(i);
  const InputError fem_dynamics = input_error([&] { FemExplicitDynamics dynamics(fem, {}, Backend::cuda); });
  const InputError fem_static = input_error([&] { solve_fem_static(fem, bc, {}, {}, Backend::cuda); });
  EXPECT_EQ(fem_dynamics.file(), "fem dynamics");
  EXPECT_EQ(fem_static.file(), "fem static");
  for (const InputError& e : {input_error([] { resolve_backend("cuda", "scene.yaml"); }),
                              input_error([] { require_backend(Backend::cuda, "step"); }),
                              input_error([] { DeviceSimulation simulation; }),
                              input_error([] { cuda_device_info(0); }), fem_dynamics, fem_static}) {
    EXPECT_EQ(e.field(), "backend");
    EXPECT_NE(e.problem().find("cuda was asked for but"), std::string::npos) << e.problem();
    EXPECT_NE(e.problem().find(why), std::string::npos) << e.problem();
    EXPECT_NE(e.problem().find("use cpu or auto"), std::string::npos) << e.problem();
  }
  EXPECT_EQ(input_error([] { DeviceSimulation simulation; }).file(), "device simulation");
}

}  // namespace
}  // namespace ctsurg::sim
