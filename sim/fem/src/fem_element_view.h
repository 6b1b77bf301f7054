// The kernels' view of a model's elements (kernels/fem_forces_impl.h) from a FemModel: its tets, the
// per-element B = Dm^-1 and volumes in the kernels' scalar T (the model's own for double, a float copy
// for the dynamics), and its materials' laws and constants.
#pragma once

#include "ctsurg/sim/fem/fem_model.h"
#include "ctsurg/sim/fem/kernels/fem_forces_impl.h"

namespace ctsurg::sim {

// dm_inverse: #T x 9, volume: #T, both kept alive by the caller as long as the view.
template <class T>
FemElementView<T> fem_element_view(const FemModel& model, const T* dm_inverse, const T* volume) {
  FemElementView<T> v;
  v.tets = model.tets.data();
  v.dm_inverse = dm_inverse;
  v.volume = volume;
  v.count = model.tet_count();
  v.order = model.order;
  v.material_count = 1;
  v.materials[0] = {model.material.law, static_cast<T>(model.lame.mu), static_cast<T>(model.lame.lambda),
                    {static_cast<T>(model.material.constants[0]), static_cast<T>(model.material.constants[1])}};
  return v;
}

// The model's own (double) element data.
inline FemElementView<double> fem_element_view(const FemModel& model) {
  return fem_element_view<double>(model, model.dm_inverse.data(), model.rest_volume.data());
}

}  // namespace ctsurg::sim
