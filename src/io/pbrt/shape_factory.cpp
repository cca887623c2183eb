#include "io/pbrt/shape_factory.h"

#include <cmath>
#include <stdexcept>

#include "io/pbrt/ply_reader.h"

namespace caustica::pbrt {

namespace {

// Vertex attributes shared by trianglemesh and bilinearmesh: P (required), N and uv
// (optional, one per vertex).
void read_vertices(const ParamList& params, const std::string& shape, const SourceLocation& where,
                   TriangleMesh* mesh) {
  const Param* p = params.find("P", {ParamType::Point3});
  if (!p) throw SceneLoadError(where, shape + ": \"point3 P\" (the vertex positions) is required");
  mesh->positions = params.get_point3s("P");
  const size_t n = mesh->positions.size();
  if (const Param* np = params.find("N", {ParamType::Normal3})) {
    mesh->normals = params.get_normals("N");
    if (mesh->normals.size() != n)
      param_error(*np, "expected one normal per vertex (" + std::to_string(n) + "), got " +
                           std::to_string(mesh->normals.size()));
  }
  if (const Param* up = params.find("uv", {ParamType::Point2, ParamType::Float})) {
    for (size_t i = 0; i + 1 < up->numbers.size(); i += 2)
      mesh->uvs.emplace_back(float(up->numbers[i]), float(up->numbers[i + 1]));
    if (up->numbers.size() % 2 != 0 || mesh->uvs.size() != n)
      param_error(*up, "expected one uv pair per vertex (" + std::to_string(n) + "), got " +
                           std::to_string(up->numbers.size()) + " numbers");
  }
  // Tangents and per-face indices (ptex) do not change the geometry.
  params.find("S");
  params.find("faceIndices");
}

void check_indices(const Param* ip, const std::vector<int>& indices, size_t vertex_count) {
  for (int i : indices)
    if (i < 0 || size_t(i) >= vertex_count)
      param_error(*ip, "vertex index " + std::to_string(i) + " is out of range (" +
                           std::to_string(vertex_count) + " vertices in \"point3 P\")");
}

TriangleMesh make_triangle_mesh(const ParamList& params, const SourceLocation& where) {
  TriangleMesh mesh;
  read_vertices(params, "trianglemesh", where, &mesh);
  const Param* ip = params.find("indices", {ParamType::Integer});
  std::vector<int> indices = params.get_ints("indices");
  if (!ip) {
    if (mesh.positions.size() != 3)
      throw SceneLoadError(
          where,
          "trianglemesh: \"integer indices\" is required unless there are exactly 3 vertices");
    indices = {0, 1, 2};
  } else {
    if (indices.size() % 3 != 0)
      param_error(*ip, "expected a multiple of 3 indices (3 per triangle), got " +
                           std::to_string(indices.size()));
    check_indices(ip, indices, mesh.positions.size());
  }
  mesh.indices.assign(indices.begin(), indices.end());
  return mesh;
}

TriangleMesh make_bilinear_mesh(const ParamList& params, const SourceLocation& where) {
  TriangleMesh mesh;
  read_vertices(params, "bilinearmesh", where, &mesh);
  const Param* ip = params.find("indices", {ParamType::Integer});
  std::vector<int> indices = params.get_ints("indices");
  if (!ip) {
    if (mesh.positions.size() != 4)
      throw SceneLoadError(
          where,
          "bilinearmesh: \"integer indices\" is required unless there are exactly 4 vertices");
    indices = {0, 1, 2, 3};
  } else {
    if (indices.size() % 4 != 0)
      param_error(*ip, "expected a multiple of 4 indices (4 per patch), got " +
                           std::to_string(indices.size()));
    check_indices(ip, indices, mesh.positions.size());
  }
  // A patch lists p00 p10 p01 p11; its boundary runs p00 p10 p11 p01, and pbrt-v4's normal
  // is cross(p10 - p00, p01 - p00), which both triangles keep.
  for (size_t i = 0; i < indices.size(); i += 4) {
    const uint32_t p00 = indices[i], p10 = indices[i + 1], p01 = indices[i + 2],
                   p11 = indices[i + 3];
    mesh.indices.insert(mesh.indices.end(), {p00, p10, p11, p00, p11, p01});
  }
  return mesh;
}

TriangleMesh make_disk(const ParamList& params) {
  const float height = params.get_float("height", 0), radius = params.get_float("radius", 1);
  const float inner = params.get_float("innerradius", 0);
  const float phi_max = radians(clamp(params.get_float("phimax", 360), 0.f, 360.f));
  TriangleMesh mesh;
  if (!(phi_max > 0) || radius == inner) return mesh;  // empty
  const int segments = std::max(4, int(std::ceil(256 * phi_max / (2 * kPi))));
  auto ring = [&](float r) {
    for (int i = 0; i <= segments; ++i) {
      const float phi = phi_max * float(i) / float(segments);
      mesh.positions.emplace_back(r * std::cos(phi), r * std::sin(phi), height);
      mesh.uvs.emplace_back(phi / phi_max, (radius - r) / (radius - inner));
    }
  };
  ring(radius);
  if (inner > 0) {
    ring(inner);
  } else {
    mesh.positions.emplace_back(0.f, 0.f, height);
    mesh.uvs.emplace_back(0.f, 1.f);
  }
  const uint32_t row = uint32_t(segments + 1);
  for (int i = 0; i < segments; ++i) {
    const uint32_t a = uint32_t(i), b = uint32_t(i + 1);
    if (inner > 0) {
      // Counter-clockwise seen from +z: the winding normal is +z, as pbrt-v4's disk normal.
      mesh.indices.insert(mesh.indices.end(), {row + a, a, b, row + a, b, row + b});
    } else {
      mesh.indices.insert(mesh.indices.end(), {row, a, b});
    }
  }
  return mesh;
}

// pbrt-v4's cylinder about the z axis: outward normal cross(dp/du, dp/dv) with u along phi
// and v from zmin to zmax, uv = (phi / phimax, (z - zmin) / (zmax - zmin)). Tessellated
// around (exact along z) with radial shading normals, as finely as the disk.
TriangleMesh make_cylinder(const ParamList& params) {
  const float radius = params.get_float("radius", 1);
  const float z0 = params.get_float("zmin", -1), z1 = params.get_float("zmax", 1);
  const float z_min = std::min(z0, z1), z_max = std::max(z0, z1);
  const float phi_max = radians(clamp(params.get_float("phimax", 360), 0.f, 360.f));
  TriangleMesh mesh;
  if (!(phi_max > 0) || !(radius > 0) || !(z_max > z_min)) return mesh;  // empty
  const int segments = std::max(4, int(std::ceil(256 * phi_max / (2 * kPi))));
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i <= segments; ++i) {
      const float u = float(i) / float(segments), phi = u * phi_max;
      const Vec3 n(std::cos(phi), std::sin(phi), 0.f);
      mesh.positions.emplace_back(radius * n.x, radius * n.y, j == 0 ? z_min : z_max);
      mesh.normals.push_back(n);
      mesh.uvs.emplace_back(u, float(j));
    }
  const uint32_t row = uint32_t(segments + 1);
  for (int i = 0; i < segments; ++i) {
    const uint32_t a = uint32_t(i), b = a + 1, c = b + row, d = a + row;
    mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
  }
  return mesh;
}

TriangleMesh make_ply(const ParamList& params, const SourceLocation& where, LoaderContext& ctx) {
  const Param* fp = params.find("filename", {ParamType::String});
  if (!fp) throw SceneLoadError(where, "plymesh: \"string filename\" is required");
  const std::string name = params.get_string("filename", "");
  const std::string path = ctx.resolve(name, fp->where);
  if (path.size() > 3 && path.substr(path.size() - 3) == ".gz")
    param_error(*fp, "gzip-compressed PLY files are not supported; decompress " +
                         quote_excerpt(name, kPathExcerpt));
  PlyMesh ply;
  try {
    ply = read_ply(path);
  } catch (const std::runtime_error& e) {
    param_error(*fp, e.what());
  }
  if (ply.skipped_faces > 0)
    ctx.warnings.warn(fp->where, "plymesh " + quote_excerpt(name, kPathExcerpt) + ": skipped " +
                                     std::to_string(ply.skipped_faces) +
                                     " faces that are neither triangles nor quads");
  TriangleMesh mesh;
  mesh.positions = std::move(ply.positions);
  mesh.normals = std::move(ply.normals);
  mesh.uvs = std::move(ply.uvs);
  mesh.indices = std::move(ply.indices);
  return mesh;
}

}  // namespace

TriangleMesh tessellate_sphere(float radius, float z_min, float z_max, float phi_max_degrees) {
  const float zlo = clamp(std::min(z_min, z_max), -radius, radius),
              zhi = clamp(std::max(z_min, z_max), -radius, radius);
  const float theta_lo = std::acos(clamp(zlo / radius, -1.f, 1.f)),
              theta_hi = std::acos(clamp(zhi / radius, -1.f, 1.f));
  const float phi_max = radians(clamp(phi_max_degrees, 0.f, 360.f));
  const int nu = std::max(4, int(std::ceil(96 * phi_max / (2 * kPi)))), nv = 48;
  TriangleMesh mesh;
  for (int j = 0; j <= nv; ++j) {
    const float v = float(j) / float(nv);
    const float theta = theta_lo + v * (theta_hi - theta_lo);
    for (int i = 0; i <= nu; ++i) {
      const float u = float(i) / float(nu);
      const float phi = u * phi_max;
      const Vec3 n(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                   std::cos(theta));
      mesh.positions.push_back(n * radius);
      mesh.normals.push_back(n);
      mesh.uvs.emplace_back(u, v);
    }
  }
  const uint32_t row = uint32_t(nu + 1);
  auto add = [&](uint32_t a, uint32_t b, uint32_t c) {
    if (length_squared(cross(mesh.positions[b] - mesh.positions[a],
                             mesh.positions[c] - mesh.positions[a])) > 0)
      mesh.indices.insert(mesh.indices.end(), {a, b, c});
  };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      // u runs along +phi, v from z_min to z_max: cross(dp/du, dp/dv) points outward.
      const uint32_t a = j * row + i, b = a + 1, c = a + 1 + row, d = a + row;
      add(a, b, c);
      add(a, c, d);
    }
  return mesh;
}

std::optional<ShapeGeometry> make_shape(const std::string& type, const ParamList& params,
                                        const SourceLocation& where, LoaderContext& ctx) {
  ShapeGeometry g;
  if (type == "trianglemesh") {
    g.mesh = make_triangle_mesh(params, where);
  } else if (type == "plymesh") {
    g.mesh = make_ply(params, where, ctx);
    if (params.find("displacement"))
      ctx.warnings.warn(where, "plymesh: displacement is not supported; ignored");
    params.find("edgelength");
  } else if (type == "bilinearmesh") {
    g.mesh = make_bilinear_mesh(params, where);
  } else if (type == "loopsubdiv") {
    ctx.warnings.warn(where, "shape \"loopsubdiv\" is not supported; rendering its control mesh");
    params.find("levels");
    g.mesh = make_triangle_mesh(params, where);
  } else if (type == "disk") {
    g.mesh = make_disk(params);
    g.quadric = true;
  } else if (type == "sphere") {
    const float radius = params.get_float("radius", 1);
    if (!(radius > 0)) {
      ctx.warnings.warn(where,
                        "sphere with radius " + std::to_string(radius) + " is empty; skipped");
      return std::nullopt;
    }
    const float z_min = params.get_float("zmin", -radius), z_max = params.get_float("zmax", radius);
    const float phi_max = params.get_float("phimax", 360);
    if (z_min > -radius || z_max < radius || phi_max < 360) {
      ctx.warnings.warn(where,
                        "partial sphere (zmin, zmax or phimax) is tessellated into triangles",
                        "partial sphere");
      g.mesh = tessellate_sphere(radius, z_min, z_max, phi_max);
      g.quadric = true;
    } else {
      g.sphere_radius = radius;
    }
  } else if (type == "cylinder") {
    g.mesh = make_cylinder(params);
    g.quadric = true;
  } else if (type == "curve" || type == "cone" || type == "paraboloid" || type == "hyperboloid" ||
             type == "nurbs" || type == "heightfield") {
    ctx.warnings.warn(where, "shape " + quote_excerpt(type) + " is not supported; skipped",
                      "shape " + type);
    params.mark_all_used();
    return std::nullopt;
  } else {
    throw SceneLoadError(where, "unknown shape " + quote_excerpt(type) +
                                    " (expected trianglemesh, plymesh, bilinearmesh, sphere, "
                                    "disk, cylinder, curve or loopsubdiv)");
  }
  return g;
}

}  // namespace caustica::pbrt
