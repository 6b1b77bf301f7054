// The options shared by the contact queries (vertex_triangle_contacts.h, vertex_tet_contacts.h).
#pragma once

#include "ctsurg/sim/base/backend.h"

namespace ctsurg::sim {

// Which pairs a query reports. Every vertex and every primitive carries an object id (one per organ,
// say); a vertex is never paired with a primitive that has it as a corner (its own triangles or tets
// touch it by construction), whatever the choice.
enum class ContactPairs {
  between_objects,  // only a vertex and a primitive of different objects
  all,              // also within one object (self-contact), less the incident primitives
};

struct ContactOptions {
  ContactPairs pairs = ContactPairs::between_objects;
  double cell_size = 0;   // mm, the hash's cell edge; 0: Teschner's rule (the primitives' average edge length)
  Backend backend = Backend::cpu;  // where the table is built and queried (cuda: a CUDA device)
  int threads = 0;        // OpenMP threads on the CPU; 0: sim/base/parallel.h's rule
};

}  // namespace ctsurg::sim
