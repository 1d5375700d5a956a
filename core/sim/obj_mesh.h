// Wavefront OBJ reading (vertices and faces only), for the Stanford bunny of glmark2-data.
#pragma once

#include <string>

#include "core/sim/mesh.h"
#include "core/util/expected.h"

namespace selfcal::sim {

// Parses `v x y z` and `f a b c ...` lines (polygons are fanned into triangles; `a/b/c` index
// forms and negative indices are accepted); other lines are ignored. Errors name path:line.
Expected<TriangleMesh> ParseObjMesh(const std::string& text, const std::string& name);
Expected<TriangleMesh> ReadObjMesh(const std::string& path);

}  // namespace selfcal::sim
