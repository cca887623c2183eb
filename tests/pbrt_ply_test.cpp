// PLY files as pbrt-v4's plymesh reads them: ASCII and binary (both byte orders), normals,
// uv under their several names, quads split into triangles.
#include <gtest/gtest.h>

#include <bit>
#include <cstring>

#include "io/pbrt/ply_reader.h"
#include "pbrt_test_util.h"

namespace caustica::pbrt {
namespace {

template <typename T>
void put(std::string* out, T v, bool big_endian) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if (big_endian == (std::endian::native == std::endian::little))
    for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  out->append(b, sizeof(T));
}

// A unit quad (as one quad face) plus a triangle, with normals and uv.
std::string binary_ply(bool big_endian) {
  std::string s =
      std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
      " 1.0\ncomment test\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
      "property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float "
      "v\n"
      "element face 2\nproperty list uint8 int vertex_indices\nend_header\n";
  const float v[5][8] = {{0, 0, 0, 0, 0, 1, 0, 0},
                         {1, 0, 0, 0, 0, 1, 1, 0},
                         {1, 1, 0, 0, 0, 1, 1, 1},
                         {0, 1, 0, 0, 0, 1, 0, 1},
                         {2, 0, 0, 0, 0, 1, 0.5f, 0.5f}};
  for (const auto& row : v)
    for (float f : row) put(&s, f, big_endian);
  put<uint8_t>(&s, 4, big_endian);
  for (int i : {0, 1, 2, 3}) put<int32_t>(&s, i, big_endian);
  put<uint8_t>(&s, 3, big_endian);
  for (int i : {1, 4, 2}) put<int32_t>(&s, i, big_endian);
  return s;
}

TEST(PbrtPly, BinaryLittleAndBigEndian) {
  for (bool big : {false, true}) {
    SCOPED_TRACE(big ? "big endian" : "little endian");
    const PlyMesh m = parse_ply(binary_ply(big));
    ASSERT_EQ(m.positions.size(), 5u);
    EXPECT_EQ(m.positions[4], Vec3(2, 0, 0));
    ASSERT_EQ(m.normals.size(), 5u);
    EXPECT_EQ(m.normals[0], Vec3(0, 0, 1));
    ASSERT_EQ(m.uvs.size(), 5u);
    EXPECT_EQ(m.uvs[2].x, 1);
    EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 1, 4, 2}));
  }
}

TEST(PbrtPly, AsciiWithStAndExtraElements) {
  const PlyMesh m = parse_ply(
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty "
      "double z\n"
      "property float s\nproperty float t\nproperty uchar red\nelement material 1\nproperty int "
      "id\n"
      "element face 1\nproperty list uchar uint vertex_index\nproperty int flags\nend_header\n"
      "0 0 0 0 0 255\n1 0 0 1 0 255\n0 1 0 0 1 255\n7\n3 0 1 2 9\n");
  EXPECT_EQ(m.positions.size(), 3u);
  EXPECT_TRUE(m.normals.empty());
  EXPECT_EQ(m.uvs.size(), 3u);
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2}));
}

TEST(PbrtPly, SkipsPolygonsWithMoreThanFourVertices) {
  const PlyMesh m = parse_ply(
      "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float "
      "z\n"
      "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 2 0\n5 0 1 2 4 3\n3 0 1 2\n");
  EXPECT_EQ(m.indices.size(), 3u);
  EXPECT_EQ(m.skipped_faces, 1u);
}

TEST(PbrtPly, MalformedFilesFailWithAReason) {
  const char* bad[] = {
      "plx\n",
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n",  // no y, z
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float "
      "z\nend_header\n0 0 0\n",
      "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty float x\nproperty "
      "float y\n"
      "property float z\nend_header\n",
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float "
      "z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 "
      "0 1 7\n",
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float "
      "z\n",
  };
  for (const char* text : bad) EXPECT_THROW(parse_ply(text), std::runtime_error) << text;
}

TEST(PbrtPly, PlymeshShapeLoadsRelativeToTheSceneFile) {
  test::TempDir dir;
  dir.write("models/q.ply", binary_ply(false));
  const std::string main = dir.write(
      "s.pbrt", test::with_camera("Shape \"plymesh\" \"string filename\" \"models/q.ply\"\n"));
  auto scene = load_pbrt(main, test::capture_warning);
  EXPECT_EQ(scene->triangle_count(), 3u);
}

TEST(PbrtPly, PlymeshErrorsPointAtTheFilename) {
  test::TempDir dir;
  dir.write("bad.ply", "ply\nformat ascii 1.0\nelement vertex 1\n");
  const std::string main = dir.write(
      "s.pbrt", test::with_camera("Shape \"plymesh\"\n  \"string filename\" \"bad.ply\"\n"));
  try {
    load_pbrt(main, test::capture_warning);
    FAIL();
  } catch (const SceneLoadError& e) {
    EXPECT_EQ(e.where().line, 5);
    EXPECT_EQ(e.where().column, 3);
    EXPECT_NE(e.message().find("bad.ply"), std::string::npos);
  }
}

}  // namespace
}  // namespace caustica::pbrt
