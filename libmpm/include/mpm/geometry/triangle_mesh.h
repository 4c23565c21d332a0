#pragma once
//! Triangle meshes read from Wavefront OBJ and STL files, the input of mesh level sets.
#include <mpm/core/types.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace mpm::geometry {

struct TriangleMesh {
  std::vector<Vec<3>> vertices;                        //!< [m]
  std::vector<std::array<std::int32_t, 3>> triangles;  //!< 0-based indices into `vertices`
};

//! True when the extension of `file` is one read_triangle_mesh() knows (.obj, .stl; any case).
bool is_triangle_mesh_file(const std::string& file);

//! Reads an OBJ (`v x y z` and `f i j k ...` lines; polygons fan-triangulated; 1-based and
//! negative, i.e. relative, indices; `i/t/n` forms; other lines ignored) or an STL file (binary
//! or ASCII; equal vertices are merged). Throws InputError naming the file (and line) when the
//! file cannot be read, has an unknown extension, is malformed or holds no triangle.
TriangleMesh read_triangle_mesh(const std::string& file);

//! Throws InputError naming the file and the first edge (by its end points) that an odd number of
//! the non-degenerate triangles share: the surface has a hole or a dangling sheet, and no inside.
void check_closed(const TriangleMesh& mesh, const std::string& file);

}  // namespace mpm::geometry
