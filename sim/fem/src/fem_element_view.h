// The kernels' view of a model's elements (kernels/fem_forces_impl.h) from a FemModel: its tets, the
// per-element B = Dm^-1 and volumes in the kernels' scalar T (the model's own for double, a float copy
// for the dynamics), and its materials' laws and constants.
#pragma once

#include "ctsurg/sim/fem/fem_model.h"
#include "ctsurg/sim/fem/kernels/fem_forces_impl.h"

namespace ctsurg::sim {

// dm_inverse: #T x 9, volume: #T, both kept alive by the caller as long as the view; element_material:
// the model's (#T, or null for one material), on the device for a device view.
template <class T>
FemElementView<T> fem_element_view(const FemModel& model, const T* dm_inverse, const T* volume, const int32_t* element_material) {
  FemElementView<T> v;
  v.tets = model.tets.data();
  v.dm_inverse = dm_inverse;
  v.volume = volume;
  v.count = model.tet_count();
  v.order = model.order;
  for (std::size_t k = 0; k < model.materials.size(); ++k) {
    const FemMaterial& m = model.materials[k];
    v.materials[k] = {m.law, static_cast<T>(model.lame[k].mu), static_cast<T>(model.lame[k].lambda),
                      {static_cast<T>(m.constants[0]), static_cast<T>(m.constants[1])}};
  }
  v.element_material = element_material;
  return v;
}

// Element e's law and constants, what a double view's material(e) gives, without building the view.
inline FemLawParameters<double> fem_element_law(const FemModel& model, int32_t e) {
  const FemMaterial& m = model.material_of(e);
  const LameParameters& l = model.lame_of(e);
  return {m.law, l.mu, l.lambda, {m.constants[0], m.constants[1]}};
}

// A host view (element_material: the model's own).
template <class T>
FemElementView<T> fem_element_view(const FemModel& model, const T* dm_inverse, const T* volume) {
  return fem_element_view<T>(model, dm_inverse, volume, model.element_material.empty() ? nullptr : model.element_material.data());
}

// The model's own (double) element data.
inline FemElementView<double> fem_element_view(const FemModel& model) {
  return fem_element_view<double>(model, model.dm_inverse.data(), model.rest_volume.data());
}

}  // namespace ctsurg::sim
