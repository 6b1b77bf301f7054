// A vessel wall's section as the stiffnesses and masses of the medial-atom chain (vessel_chain.h):
// the wall is a circular tube of mid-surface radius r and thickness t (Huang et al. 2006, section 5.1,
// model the vessel by its centerline; the chain's springs here are calibrated from the wall's E and
// section instead of being tuned by hand).
//
//   A = pi ((r + t/2)^2 - (r - t/2)^2)            wall area, mm^2          (= 2 pi r t, exactly)
//   I = pi/4 ((r + t/2)^4 - (r - t/2)^4)          second moment, mm^4
//   J = 2 I                                       polar moment, mm^4
//   G = E / (2 (1 + nu))                          shear modulus, Pa
//   kappa = 2 (1 + nu) / (4 + 3 nu)               Timoshenko shear coefficient of a thin-walled
//                                                 circular tube (Cowper 1966, J. Appl. Mech. 33:335)
//   stretch EA, shear kappa G A, bending EI, torsion GJ
//
// When t/2 >= r the tube is solid (inner radius 0). The centerline's radius (the mask's maximal
// inscribed radius) is taken as the wall's mid-surface radius: CT resolves neither side of a wall a
// fraction of a millimetre thick, and the surface is drawn there.
//
// Masses: the wall's density times A per unit length, plus (blood_filled) the blood in the lumen,
// blood_density pi (r - t/2)^2: blood moves with the vessel sideways (its inertia counts when the
// vessel swings) but carries no stress. Rotational inertia per length: the wall's density times J
// (used for all three axes: exact for twist, twice the bending value, which is negligible next to the
// atoms' translational inertia in a slender chain).
//
// Units (base/particle_state.h): E in Pa = g/(mm s^2), lengths mm, density g/mm^3, so EA and kappa G A
// are uN (g mm/s^2), EI and GJ uN mm^2, mass per length g/mm, rotational inertia per length g mm.
#pragma once

#include <string>

namespace ctsurg::sim {

struct VesselWall {
  double youngs_modulus_pa = 0;    // E, Pa (> 0)
  double poisson_ratio = 0.45;     // nu, in (-1, 0.5)
  double thickness_mm = 0;         // t, mm (> 0)
  double density = 1.06e-3;        // the wall's, g/mm^3 (> 0)
  bool blood_filled = true;        // add the blood in the lumen to the mass
  double blood_density = 1.06e-3;  // g/mm^3 (whole blood 1.05-1.06 g/cm^3)
};

struct TubeSection {
  double area = 0;            // A, mm^2
  double second_moment = 0;   // I, mm^4
  double polar_moment = 0;    // J = 2 I, mm^4
  double lumen_area = 0;      // pi (r - t/2)^2, mm^2 (0 for a solid section)
};

// The section of a tube of mid-surface radius `radius_mm` and wall `thickness_mm` (both > 0).
TubeSection tube_section(double radius_mm, double thickness_mm);

struct ChainStiffness {
  double stretch = 0;               // EA, uN
  double shear = 0;                 // kappa G A, uN
  double bending = 0;               // EI, uN mm^2
  double torsion = 0;               // GJ, uN mm^2
  double mass_per_mm = 0;           // g/mm (wall, plus blood when blood_filled)
  double rotational_inertia_per_mm = 0;  // g mm
};

// The chain's constants for a wall at radius `radius_mm` (> 0). InputError("vessel", field, ...) for
// a wall out of range (E, nu, thickness, densities not finite or out of the ranges above).
ChainStiffness tube_stiffness(const VesselWall& wall, double radius_mm);
void validate_vessel_wall(const VesselWall& wall, const std::string& where);

}  // namespace ctsurg::sim
