// The Utah teapot, tessellated from Martin Newell's public-domain Bezier patch data (1975).
#pragma once

#include "core/sim/mesh.h"

namespace selfcal::sim {

// The teapot standing on z = 0, spout towards +x, handle towards -x, in Newell's units
// (height 3.15, length -3.0 .. 3.525) multiplied by `scale` [m per unit]. Each bicubic patch is
// sampled on a (subdivisions + 1)^2 grid. The lid sits loosely on the rim as in Newell's data
// (a narrow ring between radius 1.3 and 1.4 stays open) and the spout is open.
TriangleMesh MakeTeapot(double scale, int subdivisions);

}  // namespace selfcal::sim
