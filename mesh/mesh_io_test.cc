#include "mesh/mesh_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include "base/error.h"
#include "base/file_util.h"
#include "testing/testing.h"

namespace ms {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

fs::path TempDir() {
  const fs::path dir =
      fs::temp_directory_path() / ("ms_mesh_io_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

MeshWriteOptions Options(bool binary, bool float_coordinates = false) {
  MeshWriteOptions options;
  options.binary = binary;
  options.float_coordinates = float_coordinates;
  return options;
}

Mesh ColoredPyramid() {
  Mesh m;
  m.vertices = {{0.1, 0.2, 0.3}, {1.0 / 3.0, -2.5e-7, 4}, {1e6 + 0.125, 3, -1}, {-7, 8.75, 1e-300}};
  m.faces = {{0, 1, 2}, {0, 2, 3}, {0, 3, 1}, {1, 3, 2}};
  m.vertex_colors = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {17, 34, 51}};
  return m;
}

void ExpectSameMesh(const Mesh& a, const Mesh& b, double tolerance = 0) {
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  for (size_t i = 0; i < a.vertices.size(); ++i) {
    if (tolerance == 0) {
      EXPECT_EQ(a.vertices[i], b.vertices[i]) << "vertex " << i;
    } else {
      EXPECT_LE((a.vertices[i] - b.vertices[i]).norm(), tolerance * (1 + a.vertices[i].norm()))
          << "vertex " << i;
    }
  }
  EXPECT_EQ(a.faces, b.faces);
  EXPECT_EQ(a.vertex_colors, b.vertex_colors);
}

// Expects an InputError whose message names `name` and contains `fragment`.
template <typename F>
void ExpectInputError(F&& f, const std::string& name, const std::string& fragment) {
  testing::ExpectInputError(std::forward<F>(f), {name, fragment});
}

// --- Byte builders for hand-written binary files. ------------------------------------------

template <typename T>
void PutBig(std::string* s, T value) {
  char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  std::reverse(b, b + sizeof(T));  // tests run on little-endian hosts
  s->append(b, sizeof(T));
}
template <typename T>
void PutLittle(std::string* s, T value) {
  char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  s->append(b, sizeof(T));
}

// --- Round trips. -------------------------------------------------------------------------

TEST(PlyIo, BinaryRoundTripIsExactWithColours) {
  const Mesh mesh = ColoredPyramid();
  const fs::path path = TempDir() / "pyramid.ply";
  WriteMesh(mesh, path.string());
  ExpectSameMesh(mesh, ReadMesh(path.string()));
  // The header names the writer and the encoding.
  const std::string bytes = ReadFileToString(path);
  EXPECT_THAT(bytes.substr(0, 200), HasSubstr("format binary_little_endian 1.0"));
  EXPECT_THAT(bytes.substr(0, 200), HasSubstr("comment written by manisweep"));
  EXPECT_FALSE(fs::exists(TempPathFor(path)));
}

TEST(PlyIo, AsciiRoundTripIsExact) {
  Mesh mesh = ColoredPyramid();
  const fs::path path = TempDir() / "pyramid_ascii.ply";
  WriteMesh(mesh, path.string(), Options(false));
  ExpectSameMesh(mesh, ReadMesh(path.string()));
  EXPECT_THAT(ReadFileToString(path), HasSubstr("format ascii 1.0"));
  mesh.vertex_colors.clear();
  WriteMesh(mesh, path.string(), Options(false));
  EXPECT_THAT(ReadFileToString(path), ::testing::Not(HasSubstr("red")));
  ExpectSameMesh(mesh, ReadMesh(path.string()));
}

TEST(PlyIo, FloatCoordinatesRoundToFloat) {
  const Mesh mesh = ColoredPyramid();
  for (bool binary : {true, false}) {
    const fs::path path = TempDir() / "pyramid_float.ply";
    WriteMesh(mesh, path.string(), Options(binary, true));
    const Mesh back = ReadMesh(path.string());
    ASSERT_EQ(back.vertices.size(), mesh.vertices.size());
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(back.vertices[i][k],
                  static_cast<double>(static_cast<float>(mesh.vertices[i][k])));
      }
    }
    EXPECT_EQ(back.faces, mesh.faces);
  }
}

TEST(PlyIo, EmptyMeshRoundTrips) {
  const fs::path path = TempDir() / "empty.ply";
  WriteMesh(Mesh{}, path.string());
  const Mesh back = ReadMesh(path.string());
  EXPECT_EQ(back.NumVertices(), 0u);
  EXPECT_EQ(back.NumFaces(), 0u);
}

TEST(PlyIo, BigEndianWithOddTypesPolygonsAndSkippedData) {
  // Vertex: double x, float y, short z, int junk (skipped), uchar r g b, list of floats
  // (skipped). An unknown element before the faces; faces with a flags byte and a ushort/uint
  // list, one quad; an unknown element at the end.
  std::string s =
      "ply\r\nformat binary_big_endian 1.0\r\ncomment hand made\r\n"
      "element vertex 4\r\n"
      "property float64 x\r\nproperty float32 y\r\nproperty int16 z\r\nproperty int junk\r\n"
      "property uchar red\r\nproperty uchar green\r\nproperty uchar blue\r\n"
      "property list uchar float texture\r\n"
      "element camera 1\r\nproperty double focal\r\nproperty list int uchar name\r\n"
      "element face 2\r\nproperty uchar flags\r\nproperty list ushort uint vertex_indices\r\n"
      "element edge 1\r\nproperty int vertex1\r\nproperty int vertex2\r\n"
      "end_header\r\n";
  const double xs[4] = {0.5, -1.25, 3, 1e10};
  const float ys[4] = {1.5f, 2.0f, -0.25f, 7.0f};
  const int16_t zs[4] = {-3, 0, 32767, -32768};
  for (int i = 0; i < 4; ++i) {
    PutBig(&s, xs[i]);
    PutBig(&s, ys[i]);
    PutBig(&s, zs[i]);
    PutBig(&s, int32_t{-12345});
    s += static_cast<char>(10 * i);
    s += static_cast<char>(200);
    s += static_cast<char>(255);
    s += static_cast<char>(i % 2 == 0 ? 2 : 0);
    if (i % 2 == 0) {
      PutBig(&s, 0.5f);
      PutBig(&s, 0.25f);
    }
  }
  PutBig(&s, 1234.5);
  PutBig(&s, int32_t{3});
  s += "cam";
  s += static_cast<char>(7);
  PutBig(&s, uint16_t{4});
  for (uint32_t v : {0u, 1u, 2u, 3u}) PutBig(&s, v);
  s += static_cast<char>(0);
  PutBig(&s, uint16_t{3});
  for (uint32_t v : {3u, 2u, 1u}) PutBig(&s, v);
  PutBig(&s, int32_t{0});
  PutBig(&s, int32_t{1});

  const Mesh m = ParseMesh(s, MeshFormat::kPly, "be.ply");
  ASSERT_EQ(m.NumVertices(), 4u);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(m.vertices[i], Eigen::Vector3d(xs[i], ys[i], zs[i])) << i;
    EXPECT_EQ(m.vertex_colors[i], (std::array<uint8_t, 3>{uint8_t(10 * i), 200, 255}));
  }
  // The quad is fanned from its first corner.
  EXPECT_EQ(m.faces, (std::vector<std::array<int32_t, 3>>{{0, 1, 2}, {0, 2, 3}, {3, 2, 1}}));

  // Declared little-endian, the big-endian list counts become huge and are caught.
  std::string le = s;
  le.replace(le.find("binary_big_endian"), strlen("binary_big_endian"), "binary_little_endian");
  EXPECT_THROW(ParseMesh(le, MeshFormat::kPly, "le.ply"), InputError);
}

TEST(PlyIo, AsciiWithVertexIndexNameIntColoursAndUnknownElements) {
  const std::string s =
      "ply\nformat ascii 1.0\nobj_info test\n"
      "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
      "property float nx\nproperty float ny\nproperty float nz\n"
      "property float red\nproperty float green\nproperty float blue\nproperty float alpha\n"
      "element material 2\nproperty list int int ids\nproperty uchar kind\n"
      "element face 2\nproperty list char int vertex_index\nproperty int tag\n"
      "end_header\n"
      "0 0 0 nan nan nan 1 0 0.5 1\n"
      "1 0 0 0 0 1 0 1 0 1\n"
      "1 1 0 0 0 1 0 0 1 1\n"
      "0 1 0 0 0 1 1 1 1 1\n"
      "+0.5 5e-1 -1.0E+0 0 0 1 0.2 0.4 0.6 1\n"
      "3 1 2 3 9\n"
      "0 4\n"
      "5 0 1 2 3 4 -1\n"
      "3 4 3 2 7\n\n";
  const Mesh m = ParseMesh(s, MeshFormat::kPly, "a.ply");
  ASSERT_EQ(m.NumVertices(), 5u);
  EXPECT_EQ(m.vertices[4], Eigen::Vector3d(0.5, 0.5, -1));
  EXPECT_EQ(m.vertex_colors[0], (std::array<uint8_t, 3>{255, 0, 128}));
  EXPECT_EQ(m.vertex_colors[4], (std::array<uint8_t, 3>{51, 102, 153}));
  EXPECT_EQ(m.faces,
            (std::vector<std::array<int32_t, 3>>{{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {4, 3, 2}}));
}

TEST(PlyIo, PointCloudRoundTrips) {
  PointCloud cloud;
  cloud.points = {{1, 2, 3}, {-4.5, 5.25, 1.0 / 7.0}, {0, 0, 0}};
  cloud.normals = {{0, 0, 1}, {0.6, 0.8, 0}, {1, 0, 0}};
  cloud.colors = {{1, 2, 3}, {250, 251, 252}, {0, 0, 0}};
  cloud.scalars = {0.5f, 0.98f, -1.0f};
  for (bool binary : {true, false}) {
    const fs::path path = TempDir() / (binary ? "points_bin.ply" : "points_ascii.ply");
    WritePointCloud(cloud, path.string(), Options(binary));
    const PointCloud back = ReadPointCloud(path.string());
    EXPECT_EQ(back.points, cloud.points);
    ASSERT_EQ(back.normals.size(), 3u);
    for (size_t i = 0; i < 3; ++i) {
      EXPECT_LE((back.normals[i] - cloud.normals[i]).norm(), 1e-7);
    }
    EXPECT_EQ(back.colors, cloud.colors);
    EXPECT_EQ(back.scalars, cloud.scalars);
    EXPECT_THAT(ReadFileToString(path).substr(0, 400), HasSubstr("property float quality"));
  }
  // Points only; `scalar` is read as a synonym of `quality`; faces in the file are skipped.
  const PointCloud plain = ParsePointCloud(
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\nproperty double y\n"
      "property double z\nproperty float scalar\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n1 2 3 0.25\n4 5 6 0.5\n3 0 1 1\n",
      "p.ply");
  EXPECT_EQ(plain.points.size(), 2u);
  EXPECT_TRUE(plain.normals.empty());
  EXPECT_TRUE(plain.colors.empty());
  EXPECT_EQ(plain.scalars, (std::vector<float>{0.25f, 0.5f}));
  // A mesh file read as points keeps its vertices.
  const fs::path mesh_path = TempDir() / "mesh_as_points.ply";
  WriteMesh(ColoredPyramid(), mesh_path.string());
  EXPECT_EQ(ReadPointCloud(mesh_path.string()).points, ColoredPyramid().vertices);
  EXPECT_THROW(ReadPointCloud((TempDir() / "x.obj").string()), InputError);
}

// --- Malformed PLY. ---------------------------------------------------------------------------

std::string BinaryTriangle() {
  std::string s =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\nproperty list uchar int "
      "vertex_indices\nend_header\n";
  for (float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) PutLittle(&s, v);
  s += static_cast<char>(3);
  for (int32_t v : {0, 1, 2}) PutLittle(&s, v);
  return s;
}

TEST(PlyIo, ValidBinaryTriangleParses) {
  const Mesh m = ParseMesh(BinaryTriangle(), MeshFormat::kPly, "t.ply");
  EXPECT_EQ(m.NumFaces(), 1u);
  EXPECT_FALSE(m.HasColors());
}

TEST(PlyIo, TruncatedFilesFailNamingTheFile) {
  const std::string full = BinaryTriangle();
  const size_t header = full.find("end_header\n") + strlen("end_header\n");
  for (size_t cut = header; cut < full.size(); ++cut) {
    ExpectInputError([&] { ParseMesh(full.substr(0, cut), MeshFormat::kPly, "cut.ply"); },
                     "cut.ply", "");
  }
  ExpectInputError([&] { ParseMesh(full.substr(0, 30), MeshFormat::kPly, "cut.ply"); }, "cut.ply",
                   "end_header");
  // Truncated inside the face list: the error says which face.
  ExpectInputError([&] { ParseMesh(full.substr(0, full.size() - 2), MeshFormat::kPly, "f.ply"); },
                   "f.ply", "face 0");
}

TEST(PlyIo, CountsLargerThanTheFileAreRejectedBeforeAllocating) {
  std::string s = BinaryTriangle();
  s.replace(s.find("vertex 3"), 8, "vertex 5");
  ExpectInputError([&] { ParseMesh(s, MeshFormat::kPly, "count.ply"); },
                   "count.ply:3:", "count 5 needs at least 5 x 12 bytes");
  std::string huge = BinaryTriangle();
  huge.replace(huge.find("face 1"), 6, "face 18446744073709551615");
  ExpectInputError([&] { ParseMesh(huge, MeshFormat::kPly, "huge.ply"); },
                   "huge.ply:7:", "element face: count 18446744073709551615");
  std::string ascii_huge =
      "ply\nformat ascii 1.0\nelement vertex 1000000000000\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n0 0 0\n";
  ExpectInputError([&] { ParseMesh(ascii_huge, MeshFormat::kPly, "ah.ply"); }, "ah.ply",
                   "element vertex: count 1000000000000");
  std::string overflow = "ply\nformat ascii 1.0\nelement vertex 99999999999999999999999\n";
  ExpectInputError([&] { ParseMesh(overflow, MeshFormat::kPly, "o.ply"); },
                   "o.ply:3:", "not a non-negative integer");
  // A list whose length runs past the data.
  std::string list = BinaryTriangle();
  list[list.size() - 13] = static_cast<char>(200);
  ExpectInputError([&] { ParseMesh(list, MeshFormat::kPly, "list.ply"); }, "list.ply",
                   "runs past the end");
}

TEST(PlyIo, NonFiniteCoordinatesAreRejected) {
  std::string s = BinaryTriangle();
  const size_t header = s.find("end_header\n") + strlen("end_header\n");
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(&s[header + 4 * 4], &nan, 4);  // vertex 1, y
  ExpectInputError([&] { ParseMesh(s, MeshFormat::kPly, "nan.ply"); }, "nan.ply",
                   "vertex 1: y: value is not finite");
  const std::string ascii =
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\nproperty double y\n"
      "property double z\nend_header\n0 inf 0\n";
  ExpectInputError([&] { ParseMesh(ascii, MeshFormat::kPly, "inf.ply"); },
                   "inf.ply:8:", "not finite");
  std::string overflow = ascii;
  overflow.replace(overflow.find("0 inf 0"), 7, "0 1e999 0");
  ExpectInputError([&] { ParseMesh(overflow, MeshFormat::kPly, "big.ply"); },
                   "big.ply:8:", "y: value is not finite");
  std::string underflow = ascii;
  underflow.replace(underflow.find("0 inf 0"), 7, "0 1e-999 4.9e-324");
  EXPECT_EQ(ParseMesh(underflow, MeshFormat::kPly, "small.ply").vertices[0],
            Eigen::Vector3d(0, 0, 4.9e-324));
  ExpectInputError([] { ParseMesh("v 1 -1e400 0\n", MeshFormat::kObj, "big.obj"); },
                   "big.obj:1:", "not finite");
}

TEST(PlyIo, BadIndicesAndFacesAreRejected) {
  std::string out_of_range = BinaryTriangle();
  const int32_t bad = 3;
  std::memcpy(&out_of_range[out_of_range.size() - 4], &bad, 4);
  ExpectInputError([&] { ParseMesh(out_of_range, MeshFormat::kPly, "idx.ply"); }, "idx.ply",
                   "face 0: vertex_indices: vertex index 3 is out of range [0, 3)");
  std::string negative = BinaryTriangle();
  const int32_t minus = -1;
  std::memcpy(&negative[negative.size() - 8], &minus, 4);
  ExpectInputError([&] { ParseMesh(negative, MeshFormat::kPly, "neg.ply"); }, "neg.ply",
                   "vertex index -1");
  const std::string two =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n2 0 1\n";
  ExpectInputError([&] { ParseMesh(two, MeshFormat::kPly, "two.ply"); },
                   "two.ply:13:", "at least 3 vertices");
  const std::string neg_count =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list char int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n-3 0 1 2\n";
  ExpectInputError([&] { ParseMesh(neg_count, MeshFormat::kPly, "nc.ply"); },
                   "nc.ply:13:", "negative list length");
  const std::string range =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
      "end_header\n0 0 0 1 2 3\n1 0 0 1 2 3\n0 1 0 1 256 3\n";
  ExpectInputError([&] { ParseMesh(range, MeshFormat::kPly, "r.ply"); },
                   "r.ply:13:", "vertex 2: green: 256 is out of range");
}

TEST(PlyIo, MalformedHeadersAndLines) {
  const std::string body =
      "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
      "0 0 0\n";
  ExpectInputError([&] { ParseMesh("plx\n", MeshFormat::kPly, "h.ply"); }, "h.ply",
                   "not a PLY file");
  ExpectInputError([&] { ParseMesh("", MeshFormat::kPly, "h.ply"); }, "h.ply", "not a PLY file");
  ExpectInputError([&] { ParseMesh("ply\nformat binary 1.0\n" + body, MeshFormat::kPly, "h.ply"); },
                   "h.ply:2:", "unknown format");
  ExpectInputError([&] { ParseMesh("ply\nformat ascii 2.0\n" + body, MeshFormat::kPly, "h.ply"); },
                   "h.ply:2:", "version");
  ExpectInputError([&] { ParseMesh("ply\n" + body, MeshFormat::kPly, "h.ply"); },
                   "h.ply:2:", "'format' must come before");
  ExpectInputError(
      [&] {
        ParseMesh("ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n",
                  MeshFormat::kPly, "h.ply");
      },
      "h.ply:4:", "unknown type 'float128'");
  ExpectInputError(
      [&] {
        ParseMesh(
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty list float int x\n"
            "end_header\n",
            MeshFormat::kPly, "h.ply");
      },
      "h.ply:4:", "count type must be an integer");
  ExpectInputError(
      [&] {
        ParseMesh(
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
            "end_header\n0 0\n",
            MeshFormat::kPly, "h.ply");
      },
      "h.ply:3:", "needs scalar properties x, y and z");
  ExpectInputError(
      [&] {
        ParseMesh("ply\nformat ascii 1.0\nelement point 1\nproperty float x\nend_header\n0\n",
                  MeshFormat::kPly, "h.ply");
      },
      "h.ply", "no 'vertex' element");
  ExpectInputError(
      [&] { ParseMesh("ply\nformat ascii 1.0\n" + body + "1 1 1\n", MeshFormat::kPly, "h.ply"); },
      "h.ply", "data continues after the last element");
  ExpectInputError(
      [&] {
        ParseMesh(
            "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
            "property float z\nend_header\n0 0 0 7\n1 1 1\n",
            MeshFormat::kPly, "h.ply");
      },
      "h.ply:8:", "vertex 0: 4 values on the line, the header describes 3");
  ExpectInputError(
      [&] {
        ParseMesh(
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
            "property float z\nend_header\n0 zero 0\n",
            MeshFormat::kPly, "h.ply");
      },
      "h.ply:8:", "y: 'zero' is not a number");
  ExpectInputError(
      [&] {
        ParseMesh("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float x\n",
                  MeshFormat::kPly, "h.ply");
      },
      "h.ply:5:", "declared twice");
  ExpectInputError(
      [&] {
        ParseMesh(
            "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
            "property float z\nelement face 0\nproperty int foo\nend_header\n",
            MeshFormat::kPly, "h.ply");
      },
      "h.ply:7:", "no list property vertex_indices");
}

// --- OBJ. ---------------------------------------------------------------------------------

TEST(ObjIo, RoundTripWithColours) {
  const Mesh mesh = ColoredPyramid();
  const fs::path path = TempDir() / "pyramid.obj";
  WriteMesh(mesh, path.string());
  ExpectSameMesh(mesh, ReadMesh(path.string()));
  Mesh plain = mesh;
  plain.vertex_colors.clear();
  WriteMesh(plain, path.string());
  ExpectSameMesh(plain, ReadMesh(path.string()));
  EXPECT_THAT(ReadFileToString(path), HasSubstr("# written by manisweep"));
}

TEST(ObjIo, CornerFormsNegativeIndicesPolygonsAndIgnoredStatements) {
  const std::string s =
      "# comment\nmtllib x.mtl\no thing\n"
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0 1.0\n"
      "vt 0 0\nvn 0 0 1\ng group\nusemtl m\ns off\n"
      "f 1/1/1 2/1/1 3/1/1 4/1/1\n"
      "f -4//1 -2//1 -1//1\n"
      "f 1/1 3/1 4/1\n"
      "l 1 2\n"
      "f 5 6 7  # forward references\n"
      "v 0 0 1\nv 1 0 1\nv 0 1 1\n";
  const Mesh m = ParseMesh(s, MeshFormat::kObj, "c.obj");
  EXPECT_EQ(m.NumVertices(), 7u);
  EXPECT_EQ(m.faces, (std::vector<std::array<int32_t, 3>>{
                         {0, 1, 2}, {0, 2, 3}, {0, 2, 3}, {0, 2, 3}, {4, 5, 6}}));
  EXPECT_FALSE(m.HasColors());
  // Colours in 0..255 are recognised too.
  const Mesh c = ParseMesh("v 0 0 0 255 0 10\nv 1 0 0 0 128 0\nv 0 1 0 1 1 1\nf 1 2 3\n",
                           MeshFormat::kObj, "c255.obj");
  EXPECT_EQ(c.vertex_colors[0], (std::array<uint8_t, 3>{255, 0, 10}));
  EXPECT_EQ(c.vertex_colors[2], (std::array<uint8_t, 3>{1, 1, 1}));
  // Colours on only some vertices are dropped.
  EXPECT_FALSE(ParseMesh("v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", MeshFormat::kObj, "p.obj")
                   .HasColors());
}

TEST(ObjIo, MalformedFilesFailNamingFileAndLine) {
  ExpectInputError([] { ParseMesh("v 0 0 0\nv 1 0 0\nf 1 2 4\n", MeshFormat::kObj, "a.obj"); },
                   "a.obj:3:", "vertex index 4 is out of range");
  ExpectInputError(
      [] { ParseMesh("v 0 0 0\nv 1 0 0\nv 1 1 1\nf 1 2 0\n", MeshFormat::kObj, "b.obj"); },
      "b.obj:4:", "index 0");
  ExpectInputError([] { ParseMesh("v 0 0 0\nv 1 0 0\nf -1 -2 -3\n", MeshFormat::kObj, "c.obj"); },
                   "c.obj:3:", "relative index");
  ExpectInputError([] { ParseMesh("v 0 nan 0\n", MeshFormat::kObj, "d.obj"); },
                   "d.obj:1:", "vertex y: 'nan' is not finite");
  ExpectInputError([] { ParseMesh("v 0 0\n", MeshFormat::kObj, "e.obj"); },
                   "e.obj:1:", "found 2 numbers");
  ExpectInputError([] { ParseMesh("v 0 0 0\nv 1 0 0\nf 1 2\n", MeshFormat::kObj, "f.obj"); },
                   "f.obj:3:", "at least 3 corners");
  ExpectInputError(
      [] { ParseMesh("v 0 0 0\nv 1 0 0\nv 1 1 1\nf 1 x 3\n", MeshFormat::kObj, "g.obj"); },
      "g.obj:4:", "'x' does not start with a vertex index");
  ExpectInputError(
      [] {
        ParseMesh("v 0 0 0\nv 1 0 0\nv 1 1 1\nf 1 2 99999999999999999999\n", MeshFormat::kObj,
                  "h.obj");
      },
      "h.obj:4:", "does not start with a vertex index");
}

TEST(MeshIo, PathsAndExtensions) {
  EXPECT_EQ(MeshFormatFromPath("a/b.PLY"), MeshFormat::kPly);
  EXPECT_EQ(MeshFormatFromPath("x.Obj"), MeshFormat::kObj);
  ExpectInputError([] { MeshFormatFromPath("mesh.stl"); }, "mesh.stl",
                   "unknown mesh file extension");
  ExpectInputError([] { ReadMesh("/nonexistent/mesh.ply"); }, "/nonexistent/mesh.ply", "not found");
  ExpectInputError([] { WriteMesh(Mesh{}, "out.off"); }, "out.off", "extension");
  Mesh bad = ColoredPyramid();
  bad.faces.push_back({0, 1, 9});
  EXPECT_THROW(WriteMesh(bad, (TempDir() / "bad.ply").string()), InternalError);
  EXPECT_FALSE(fs::exists(TempDir() / "bad.ply"));
}

}  // namespace
}  // namespace ms
