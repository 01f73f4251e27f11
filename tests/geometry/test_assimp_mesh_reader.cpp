// The formats read through assimp (src/geometry/assimp_mesh_reader.cpp): STL written here in
// both encodings reads back with its triangles and bounds; a glTF's nodes place each copy of a
// mesh; assimp stays quiet; the files a glTF names are read only when they are files, within the
// size limit. (The cube in every format and the malformed corpus are in test_mesh_io.cpp.)
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>

#include "core/error.hpp"
#include "geometry/mesh_io.hpp"
#include "mesh_test_shapes.hpp"
#include "support/scratch.hpp"

namespace sandflow {
namespace {

using test::ScratchTest;

Vec3 facet_normal(const TriangleMesh& m, std::size_t t) {
  const auto& [a, b, c] = m.triangles[t];
  const Vec3 n = cross(m.vertices[b] - m.vertices[a], m.vertices[c] - m.vertices[a]);
  return n / norm(n);
}

// ASCII STL as exporters write it: a facet normal, three vertices a facet, no shared vertices.
std::string ascii_stl(const TriangleMesh& m) {
  std::string s = "solid box\n";
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    const Vec3 n = facet_normal(m, t);
    s += "  facet normal " + std::to_string(n.x) + " " + std::to_string(n.y) + " " +
         std::to_string(n.z) + "\n    outer loop\n";
    for (std::uint32_t v : m.triangles[t]) {
      const Vec3& p = m.vertices[v];
      s += "      vertex " + std::to_string(p.x) + " " + std::to_string(p.y) + " " +
           std::to_string(p.z) + "\n";
    }
    s += "    endloop\n  endfacet\n";
  }
  return s + "endsolid box\n";
}

void append_float(std::string& out, double v) {
  const auto f = static_cast<float>(v);
  char bytes[4];
  std::memcpy(bytes, &f, 4);  // little-endian, as STL is, on the machines this project runs on
  out.append(bytes, 4);
}

// Binary STL; its header starts with "solid", as some exporters write it, which must not make it
// read as ASCII.
std::string binary_stl(const TriangleMesh& m) {
  std::string s = "solid box, written as binary STL";
  s.resize(80, '\0');
  const auto count = static_cast<std::uint32_t>(m.triangles.size());
  s.append(reinterpret_cast<const char*>(&count), 4);
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    const Vec3 n = facet_normal(m, t);
    for (double c : {n.x, n.y, n.z}) append_float(s, c);
    for (std::uint32_t v : m.triangles[t])
      for (double c : {m.vertices[v].x, m.vertices[v].y, m.vertices[v].z}) append_float(s, c);
    s.append(2, '\0');  // attribute byte count
  }
  return s;
}

class AssimpMeshReader : public ScratchTest {};

// A tetrahedron used by two nodes, its buffer in tetra.bin
constexpr const char* kTetraGltf = R"({
  "asset": {"version": "2.0"},
  "scene": 0,
  "scenes": [{"nodes": [0]}],
  "nodes": [
    {"children": [1, 2], "translation": [0, 10, 0]},
    {"mesh": 0, "translation": [1, 0, 0]},
    {"mesh": 0, "translation": [0, 0, 5], "scale": [2, 2, 2]}
  ],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
  "buffers": [{"uri": "tetra.bin", "byteLength": 72}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                  {"buffer": 0, "byteOffset": 48, "byteLength": 24}],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
     "min": [0, 0, 0], "max": [1, 1, 1]},
    {"bufferView": 1, "componentType": 5123, "count": 12, "type": "SCALAR"}
  ]
})";

// A closed box of 0.5 x 0.25 x 0.125 m (exact in float) away from the origin: 12 facets, whose 36
// corners join into 8 vertices although each facet carries its own normal; metres as written.
TEST_F(AssimpMeshReader, StlWrittenHereReadsBackInBothEncodings) {
  const Vec3 lo{1, -2, 0.5}, hi{1.5, -1.75, 0.625};
  const TriangleMesh box = test::box_mesh(lo, hi);
  const std::string ascii = folder_.write("box.stl", ascii_stl(box));
  const std::string binary = folder_.write("box_binary.stl", binary_stl(box));
  for (const std::string& path : {ascii, binary}) {
    SCOPED_TRACE(path);
    const TriangleMesh m = load_mesh(path);
    EXPECT_EQ(m.triangles.size(), 12u);
    EXPECT_EQ(m.vertices.size(), 8u);
    const Aabb b = mesh_bounds(m);
    EXPECT_EQ(b.lo, lo);
    EXPECT_EQ(b.hi, hi);
    const MeshQuality q = mesh_quality(m);
    EXPECT_TRUE(q.closed());
    EXPECT_TRUE(q.manifold());
    EXPECT_EQ(q.degenerate_triangles, 0u);
  }
}

// One tetrahedron, used by two nodes under a parent: the parent moves both by (0, 10, 0), one
// child by (1, 0, 0), the other scales by 2 and moves by (0, 0, 5). The buffer is a .bin beside
// the .gltf.
TEST_F(AssimpMeshReader, GltfNodesPlaceEachUseOfAMesh) {
  std::string bin;
  for (double c : {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}) append_float(bin, c);
  for (std::uint16_t i : {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3})
    bin.append(reinterpret_cast<const char*>(&i), 2);
  folder_.write("tetra.bin", bin);
  const std::string gltf = folder_.write("tetra.gltf", kTetraGltf);
  const TriangleMesh m = load_mesh(gltf);
  EXPECT_EQ(m.triangles.size(), 8u);
  EXPECT_EQ(m.vertices.size(), 8u);
  const Aabb b = mesh_bounds(m);
  EXPECT_EQ(b.lo, Vec3(0, 10, 0));  // the second copy reaches x = 0
  EXPECT_EQ(b.hi, Vec3(2, 12, 7));
  EXPECT_TRUE(mesh_quality(m).closed());
  // the scaled copy: (0, 0, 1) -> (0, 0, 2) + (0, 0, 5) + (0, 10, 0)
  bool found = false;
  for (const Vec3& p : m.vertices) found = found || p == Vec3(0, 10, 7);
  EXPECT_TRUE(found);
}

// Assimp prints nothing, whether it reads a file or refuses it.
TEST_F(AssimpMeshReader, AssimpPrintsNothing) {
  const std::string data = std::string(SANDFLOW_SOURCE_DIR) + "/tests/data/meshes/";
  ::testing::internal::CaptureStdout();
  ::testing::internal::CaptureStderr();
  EXPECT_NO_THROW(load_mesh(data + "cube.glb"));
  EXPECT_THROW(load_mesh(data + "bad/stl_four_vertices_ascii.stl"), InputError);
  EXPECT_THROW(load_mesh(data + "bad/gltf_index_out_of_range.gltf"), InputError);
  EXPECT_EQ(::testing::internal::GetCapturedStdout(), "");
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
}

// A glTF names other files beside it; a FIFO there is never opened (it would block).
TEST_F(AssimpMeshReader, AGltfBufferThatIsNotAFileIsRefused) {
  ASSERT_EQ(::mkfifo(path("tetra.bin").c_str(), 0600), 0);
  const std::string gltf = folder_.write("tetra.gltf", kTetraGltf);
  try {
    load_mesh(gltf);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(gltf + ": the file it names, '"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("tetra.bin', is a FIFO, not a file"), std::string::npos)
        << e.what();
  }
}

// Assimp takes up to 23 times a file's size in memory: a file read through it is refused above
// kMaxAssimpMeshBytes, before assimp sees it, and so are the files a glTF names, together with it
// (here a sparse file, which takes no disk).
TEST_F(AssimpMeshReader, FilesAboveTheirLimitAreRefusedUnread) {
  const std::string big(kMaxAssimpMeshBytes + 1, ' ');
  EXPECT_THROW(parse_mesh(big, MeshFormat::Stl, "big.stl"), InputError);
  folder_.write("tetra.bin", "");
  std::filesystem::resize_file(path("tetra.bin"), kMaxAssimpMeshBytes);
  const std::string gltf = folder_.write("tetra.gltf", kTetraGltf);
  try {
    load_mesh(gltf);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(
        std::string(e.what()).find("more than the limit of " + std::to_string(kMaxAssimpMeshBytes)),
        std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace sandflow
