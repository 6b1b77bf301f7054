// The material laws of the tetrahedral FEM and the one place that chooses among them: each law is a
// header of its own in this folder (fem_law_types.h says what a law provides); fem_visit_law is the only
// switch over FemLaw, so -Wswitch (an error in this build) names a law that is missing from it.
//
// Adding a law (docs/architecture.md, "Adding a material law"): its header here, its id in FemLaw
// (fem_law_types.h), its case below; its scenario name, constants and checks come from its kInfo.
#pragma once

#include "ctsurg/sim/fem/laws/corotational.h"
#include "ctsurg/sim/fem/laws/fem_law_types.h"
#include "ctsurg/sim/fem/laws/linear.h"
#include "ctsurg/sim/fem/laws/mooney_rivlin.h"
#include "ctsurg/sim/fem/laws/neo_hookean.h"
#include "ctsurg/sim/fem/laws/stvk.h"

namespace ctsurg::sim {

// v(Law{}) for the law `law` (host and device: v's operator() must be callable where this is).
#if defined(__CUDACC__)
#pragma nv_exec_check_disable
#endif
template <class Visitor>
CTSURG_HD inline auto fem_visit_law(FemLaw law, const Visitor& v) -> decltype(v(LinearLaw{})) {
  switch (law) {
    case FemLaw::linear: return v(LinearLaw{});
    case FemLaw::stvk: return v(StvkLaw{});
    case FemLaw::neo_hookean: return v(NeoHookeanLaw{});
    case FemLaw::corotational: return v(CorotationalLaw{});
    case FemLaw::mooney_rivlin: return v(MooneyRivlinLaw{});
  }
  return v(NeoHookeanLaw{});  // not reached: materials are validated when a model is built
}

// The dispatched law functions (fem_law_types.h). P, A zero and false when det F <= 0 (an inverted
// element, reported by the caller) for every law; the energy is 1e30 there for the laws that need J > 0.
template <class T>
struct FemLawFirstPiola {
  const FemLawParameters<T>& k;
  const T* F;
  T J;
  T* P;
  template <class Law>
  CTSURG_HD void operator()(Law) const { Law::first_piola(k, F, J, P); }
};

template <class T>
struct FemLawEnergyDensity {
  const FemLawParameters<T>& k;
  const T* F;
  template <class Law>
  CTSURG_HD T operator()(Law) const {
    if (Law::kNeedsPositiveJ && !(det3(F) > T(0))) return T(1e30);
    return Law::energy_density(k, F);
  }
};

template <class T>
struct FemLawTangent {
  const FemLawParameters<T>& k;
  const T* F;
  T J;
  T* A;
  template <class Law>
  CTSURG_HD void operator()(Law) const { Law::tangent(k, F, J, A); }
};

struct FemLawTraits {
  bool needs_positive_j;
  bool indefinite_tangent;
  template <class Law>
  CTSURG_HD FemLawTraits operator()(Law) const { return {Law::kNeedsPositiveJ, Law::kIndefiniteTangent}; }
};

// The law's traits (fem_law_types.h).
CTSURG_HD inline FemLawTraits fem_law_traits(FemLaw law) { return fem_visit_law(law, FemLawTraits{}); }

}  // namespace ctsurg::sim
