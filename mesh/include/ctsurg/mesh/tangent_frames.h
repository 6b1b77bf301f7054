// Per-vertex tangent frames of a texture-mapped triangle mesh: the frame a tangent-space normal map
// is expressed in, with glTF 2.0's TANGENT convention (xyz unit tangent, w = +-1 handedness,
// bitangent = w * cross(normal, tangent)).
//
// Per triangle, the derivatives of position with respect to the texture coordinates,
//   dP/du = (e1 dv2 - e2 dv1) / r,  dP/dv = (e2 du1 - e1 du2) / r,  r = du1 dv2 - du2 dv1
// (e1, e2 the edges from corner 0; du, dv their UV differences), are normalised and accumulated at
// each corner weighted by the corner angle, as MikkTSpace does (Mikkelsen 2008, "Simulation of
// wrinkled surfaces revisited", section 4). At each vertex the accumulated dP/du is orthogonalised
// against the vertex normal (Gram-Schmidt) and normalised; w is +1 when cross(normal, tangent)
// points along -dP/dv, i.e. up the image (v runs down the image in glTF, and glTF normal maps have
// green pointing up), else -1. Triangles with a degenerate UV or 3D area contribute nothing; a
// vertex left without a tangent gets a unit vector orthogonal to its normal (deterministic) and w = +1.
// Sequential over triangles in order: deterministic.
#pragma once

#include <cstdint>
#include <vector>

namespace ctsurg {

// vertices #V x 3 (LPS mm), normals #V x 3 (unit), triangles #F x 3, uvs #V x 2.
// Returns #V x 4: unit tangent (LPS) orthogonal to the normal, then w = +-1.
// Throws InputError("tangent frames", ...) when the array sizes disagree.
std::vector<float> tangent_frames(const std::vector<float>& vertices, const std::vector<float>& normals,
                                  const std::vector<uint32_t>& triangles, const std::vector<float>& uvs);

}  // namespace ctsurg
