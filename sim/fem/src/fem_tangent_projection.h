// Positive semi-definite projection of an element's material tangent A = dP/dF (9 x 9): A's negative
// eigenvalues set to zero (Teran, Sifakis, Irving and Fedkiw 2005, "Robust quasistatic finite elements
// and flesh simulation", section 5, the per-element definiteness fix; done here on A, so K = V G^T A G
// is PSD too). St. Venant-Kirchhoff under compression and Neo-Hookean far from rest have indefinite
// tangents; projected, every Newton tangent has a Cholesky factor and every step descends.
//
// A positive definite A (the usual case near rest) is left exactly as it is: a 9 x 9 Cholesky
// attempt decides, and only the elements that fail it pay for an eigendecomposition.
#pragma once

namespace ctsurg::sim::cpu {

// A: 81 values, symmetric, row-major; projected in place. Returns whether it changed.
bool project_tangent_psd(double* A);

}  // namespace ctsurg::sim::cpu
