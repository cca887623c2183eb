// Reads triangle meshes from PLY files (ASCII, binary little and big endian), as pbrt-v4's
// "plymesh" uses them: vertex x y z, optional nx ny nz, optional texture coordinates
// (u v, s t, texture_u texture_v or texture_s texture_t); faces as lists of vertex indices
// (`vertex_indices` or `vertex_index`). Triangles are kept, quads become two triangles,
// other polygons are skipped and counted. Other elements and properties are skipped.
#pragma once

#include <string>
#include <vector>

#include "core/vec.h"

namespace caustica::pbrt {

struct PlyMesh {
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;  // empty if the file has none
  std::vector<Vec2> uvs;      // empty if the file has none
  std::vector<uint32_t> indices;
  size_t skipped_faces = 0;  // faces with fewer than 3 or more than 4 vertices
};

// Parses PLY data held in memory. Throws std::runtime_error with a message that says what
// is wrong (without the file name).
PlyMesh parse_ply(const std::string& data);

// Reads and parses a file; errors name the file.
PlyMesh read_ply(const std::string& path);

}  // namespace caustica::pbrt
