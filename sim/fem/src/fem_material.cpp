#include "ctsurg/sim/fem/fem_material.h"

#include "ctsurg/sim/fem/kernels/fem_element_impl.h"

#include "ctsurg/core/error.h"

#include <cmath>
#include <sstream>
#include <string>

namespace ctsurg::sim {
namespace {

struct InfoOf {
  template <class Law>
  const FemLawInfo& operator()(Law) const { return Law::kInfo; }
};

// The law's own check (fem_law_types.h), for the laws that have one.
struct ProblemOf {
  const FemLawParameters<double>& k;
  template <class Law>
  FemLawProblem operator()(Law) const {
    if constexpr (requires { Law::problem(k); }) {
      return Law::problem(k);
    } else {
      return {nullptr, nullptr};
    }
  }
};


// mu and lambda of E and nu (unchecked: validate_fem_material's callers and it itself).
LameParameters lame_of(double e, double nu) { return {e / (2 * (1 + nu)), e * nu / ((1 + nu) * (1 - 2 * nu))}; }

bool valid_law(FemLaw law) {
  const auto id = static_cast<int32_t>(law);
  return id >= 0 && id < kFemLawCount;
}

FemLawParameters<double> parameters_without_constants(FemLaw law, const LameParameters& lame) {
  if (!valid_law(law)) throw InputError("fem material", "law", "unknown law id " + std::to_string(static_cast<int32_t>(law)));
  if (fem_law_info(law).constant_count > 0) {
    throw InputError("fem material", "law", std::string(fem_law_name(law)) + " has constants of its own: pass its FemLawParameters");
  }
  return {law, lame.mu, lame.lambda, {0, 0}};
}

}  // namespace

const FemLawInfo& fem_law_info(FemLaw law) { return fem_visit_law(law, InfoOf{}); }

const char* fem_law_name(FemLaw law) { return valid_law(law) ? fem_law_info(law).name : "unknown"; }

std::optional<FemLaw> fem_law_named(const std::string& name) {
  for (int32_t id = 0; id < kFemLawCount; ++id)
    if (name == fem_law_info(static_cast<FemLaw>(id)).name) return static_cast<FemLaw>(id);
  return std::nullopt;
}

std::string fem_law_names() {
  std::string names;
  for (int32_t id = 0; id < kFemLawCount; ++id) names += (id ? ", " : "") + std::string(fem_law_info(static_cast<FemLaw>(id)).name);
  return names;
}

std::optional<double> fem_youngs_modulus_from_constants(FemLaw law, const std::array<double, kFemLawConstants>& c,
                                                        double poisson_ratio) {
  if (!valid_law(law)) return std::nullopt;
  const FemLawInfo& info = fem_law_info(law);
  if (info.constant_count == 0) return std::nullopt;
  double mu = 0;
  bool sets_stiffness = false;
  for (int i = 0; i < info.constant_count; ++i) {
    mu += info.shear_weights[i] * c[static_cast<size_t>(i)];
    sets_stiffness = sets_stiffness || info.shear_weights[i] != 0;
  }
  if (!sets_stiffness) return std::nullopt;
  return 2 * mu * (1 + poisson_ratio);
}

FemMaterial fem_material_from_constants(FemLaw law, const std::array<double, kFemLawConstants>& constants, double poisson_ratio,
                                        double density) {
  FemMaterial m;
  m.law = law;
  m.constants = constants;
  m.poisson_ratio = poisson_ratio;
  m.density = density;
  const auto e = fem_youngs_modulus_from_constants(law, constants, poisson_ratio);
  if (!e) throw InputError("fem material", "law", std::string(fem_law_name(law)) + "'s constants do not set its stiffness: give youngs_modulus");
  m.youngs_modulus = *e;
  validate_fem_material(m);
  return m;
}

namespace {

void check_law_problem(const FemMaterial& m, const char* where) {
  const double nu = m.poisson_ratio;
  const LameParameters l = lame_of(m.youngs_modulus, nu);
  const FemLawParameters<double> k{m.law, l.mu, l.lambda, {m.constants[0], m.constants[1]}};
  const FemLawProblem p = fem_visit_law(m.law, ProblemOf{k});
  if (p.problem == nullptr) return;
  std::string constants;
  const FemLawInfo& info = fem_law_info(m.law);
  for (int i = 0; i < info.constant_count; ++i) constants += std::string(", ") + info.constant_names[i] + " " + message_number(m.constants[static_cast<size_t>(i)]);
  throw InputError(where, p.field, std::string(p.problem) + " (mu " + message_number(k.mu) + " Pa, lambda " + message_number(k.lambda) + " Pa at poisson_ratio " +
                                       message_number(nu) + constants + ")");
}

}  // namespace

void validate_fem_material(const FemMaterial& m, const char* where) {
  if (!valid_law(m.law))
    throw InputError(where, "law", "must be one of " + fem_law_names() + ", got id " + std::to_string(static_cast<int32_t>(m.law)));
  if (!(std::isfinite(m.youngs_modulus) && m.youngs_modulus > 0))
    throw InputError(where, "youngs_modulus", "Young's modulus must be finite and > 0 Pa, got " + std::to_string(m.youngs_modulus));
  if (!(std::isfinite(m.poisson_ratio) && m.poisson_ratio > -1 && m.poisson_ratio < 0.5))
    throw InputError(where, "poisson_ratio",
                     "Poisson's ratio must lie in (-1, 0.5) (0.5 = incompressible, not supported by this "
                     "displacement formulation), got " + std::to_string(m.poisson_ratio));
  if (!(std::isfinite(m.density) && m.density > 0))
    throw InputError(where, "density", "density must be finite and > 0 g/mm^3, got " + std::to_string(m.density));
  const FemLawInfo& info = fem_law_info(m.law);
  for (int i = 0; i < kFemLawConstants; ++i) {
    const double c = m.constants[static_cast<size_t>(i)];
    if (i >= info.constant_count) {
      if (c != 0) throw InputError(where, "constants", std::string(info.name) + " reads " + std::to_string(info.constant_count) + " constants; constant " + std::to_string(i) + " is " + message_number(c));
      continue;
    }
    if (!(std::isfinite(c) && c >= 0))
      throw InputError(where, info.constant_names[i], std::string(info.name) + "'s " + info.constant_names[i] + " must be finite and >= 0 Pa, got " + message_number(c));
  }
  if (const auto e = fem_youngs_modulus_from_constants(m.law, m.constants, m.poisson_ratio)) {
    if (!(*e > 0)) {
      throw InputError(where, info.constant_names[0], std::string(info.name) + "'s constants give no stiffness (small-strain shear modulus " +
                                                          message_number(*e / (2 * (1 + m.poisson_ratio))) + " Pa)");
    }
    if (std::abs(m.youngs_modulus - *e) > 1e-9 * *e) {
      throw InputError(where, "youngs_modulus", std::string(info.name) + "'s stiffness is set by its constants (E = " + message_number(*e) + " Pa); got " +
                                                    message_number(m.youngs_modulus));
    }
  }
  check_law_problem(m, where);
}

LameParameters lame_parameters(const FemMaterial& m) {
  validate_fem_material(m);
  return lame_of(m.youngs_modulus, m.poisson_ratio);
}

FemLawParameters<double> fem_law_parameters(const FemMaterial& m) {
  const LameParameters l = lame_parameters(m);
  return {m.law, l.mu, l.lambda, {m.constants[0], m.constants[1]}};
}

bool first_piola_kirchhoff(const FemLawParameters<double>& law, const std::array<double, 9>& F, std::array<double, 9>& P) {
  return fem_first_piola<double>(law, F.data(), P.data());
}

double strain_energy_density(const FemLawParameters<double>& law, const std::array<double, 9>& F) {
  const double w = fem_energy_density<double>(law, F.data());
  return fem_law_traits(law.law).needs_positive_j && !(det3(F.data()) > 0) ? HUGE_VAL : w;
}

bool material_tangent(const FemLawParameters<double>& law, const std::array<double, 9>& F, std::array<double, 81>& A) {
  return fem_material_tangent<double>(law, F.data(), A.data());
}

bool first_piola_kirchhoff(FemLaw law, const LameParameters& lame, const std::array<double, 9>& F, std::array<double, 9>& P) {
  return first_piola_kirchhoff(parameters_without_constants(law, lame), F, P);
}

double strain_energy_density(FemLaw law, const LameParameters& lame, const std::array<double, 9>& F) {
  return strain_energy_density(parameters_without_constants(law, lame), F);
}

}  // namespace ctsurg::sim
