// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/io/mesh_io.h"

#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "gcpstereo/core/error.h"
#include "test_data.h"

namespace gcpstereo::io {
namespace {

// A 4×3 vertex grid (a depth-map mesh in miniature) with distinct colours, 12 triangles.
TriangleMesh MakeGridMesh() {
  TriangleMesh mesh;
  const int cols = 4, rows = 3;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      mesh.vertices.emplace_back(0.5f * c, -0.25f * r, 3.0f + 0.125f * (r * cols + c));
      mesh.colors.emplace_back(static_cast<std::uint8_t>(20 * c), static_cast<std::uint8_t>(70 * r),
                               static_cast<std::uint8_t>(255 - 10 * (r * cols + c)));
    }
  }
  for (int r = 0; r + 1 < rows; ++r) {
    for (int c = 0; c + 1 < cols; ++c) {
      const int i = r * cols + c;
      mesh.faces.emplace_back(i, i + cols, i + 1);
      mesh.faces.emplace_back(i + 1, i + cols, i + cols + 1);
    }
  }
  return mesh;
}

using Key = std::tuple<float, float, float>;

// Position → colour over a mesh (importers may duplicate vertices, e.g. OBJ per face corner).
std::map<Key, Eigen::Matrix<std::uint8_t, 3, 1>> ColorByPosition(const TriangleMesh& mesh) {
  std::map<Key, Eigen::Matrix<std::uint8_t, 3, 1>> out;
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    const auto& p = mesh.vertices[v];
    out[Key(p.x(), p.y(), p.z())] =
        mesh.colors.empty() ? Eigen::Matrix<std::uint8_t, 3, 1>::Zero() : mesh.colors[v];
  }
  return out;
}

TEST(MeshIo, PlyRoundTripKeepsVerticesFacesAndColors) {
  const std::string dir = testing::MakeTempDir("io-mesh");
  const TriangleMesh mesh = MakeGridMesh();
  WriteMeshPly(dir + "/mesh.ply", mesh);
  EXPECT_FALSE(std::filesystem::exists(dir + "/mesh.ply.partial"));
  const TriangleMesh back = ReadMeshPly(dir + "/mesh.ply");
  ASSERT_EQ(back.vertices.size(), mesh.vertices.size());
  ASSERT_EQ(back.colors.size(), mesh.vertices.size());
  ASSERT_EQ(back.faces.size(), mesh.faces.size());
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    EXPECT_EQ(back.vertices[v], mesh.vertices[v]) << v;
    EXPECT_EQ(back.colors[v], mesh.colors[v]) << v;
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f) EXPECT_EQ(back.faces[f], mesh.faces[f]) << f;
  // Binary PLY as the contract says.
  std::ifstream in(dir + "/mesh.ply", std::ios::binary);
  std::string head(64, '\0');
  in.read(&head[0], 64);
  EXPECT_NE(head.find("format binary_little_endian"), std::string::npos) << head;
}

TEST(MeshIo, ObjRoundTripKeepsPositionsAndColors) {
  const std::string dir = testing::MakeTempDir("io-mesh");
  const TriangleMesh mesh = MakeGridMesh();
  WriteMeshObj(dir + "/mesh.obj", mesh);
  const TriangleMesh back = ReadMeshPly(dir + "/mesh.obj");
  EXPECT_EQ(back.faces.size(), mesh.faces.size());
  const auto expected = ColorByPosition(mesh);
  const auto actual = ColorByPosition(back);
  ASSERT_EQ(actual.size(), expected.size());  // same set of distinct positions
  for (const auto& [position, color] : expected) {
    const auto it = actual.find(position);
    ASSERT_NE(it, actual.end());
    // OBJ stores colours as text floats in [0, 1]: allow one step of rounding.
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(int(it->second[k]), int(color[k]), 1);
  }
  // Each face of the re-read mesh has the same three positions as an original face.
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(back.vertices[back.faces[f][k]], mesh.vertices[mesh.faces[f][k]]) << f << " " << k;
    }
  }
}

// OBJ positions are text: every float must come back as the same float through assimp's reader,
// also for values with no short decimal (random positions, not the grid's multiples of 1/8).
TEST(MeshIo, ObjKeepsArbitraryFloatsAndWritesNormals) {
  const std::string dir = testing::MakeTempDir("io-mesh");
  TriangleMesh mesh;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
  const int cols = 40, rows = 30;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const float z = 5.0f + 3.0f * uniform(rng);
      mesh.vertices.emplace_back((c - 20) * z / 1500.0f, (r - 15) * z / 1500.0f, z);
    }
  }
  for (int r = 0; r + 1 < rows; ++r) {
    for (int c = 0; c + 1 < cols; ++c) {
      const int i = r * cols + c;
      mesh.faces.emplace_back(i, i + cols, i + 1);
      mesh.faces.emplace_back(i + 1, i + cols, i + cols + 1);
    }
  }
  std::vector<Eigen::Vector3f> normals(mesh.vertices.size());
  for (Eigen::Vector3f& n : normals)
    n = Eigen::Vector3f(uniform(rng), uniform(rng), 1.0f).normalized();
  WriteMeshObj(dir + "/random.obj", mesh, normals);

  const TriangleMesh back = ReadMeshPly(dir + "/random.obj");
  ASSERT_EQ(back.faces.size(), mesh.faces.size());
  int mismatches = 0;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      mismatches += back.vertices[back.faces[f][k]] != mesh.vertices[mesh.faces[f][k]];
    }
  }
  EXPECT_EQ(mismatches, 0);

  // One `vn` line per vertex, in order, and faces that name the vertex's own normal.
  std::ifstream in(dir + "/random.obj");
  std::string line;
  std::vector<Eigen::Vector3f> read_normals;
  std::string first_face;
  while (std::getline(in, line)) {
    if (line.rfind("vn ", 0) == 0) {
      std::istringstream fields(line.substr(3));
      Eigen::Vector3f n;
      fields >> n.x() >> n.y() >> n.z();
      read_normals.push_back(n);
    } else if (first_face.empty() && line.rfind("f ", 0) == 0) {
      first_face = line;
    }
  }
  ASSERT_EQ(read_normals.size(), normals.size());
  for (size_t v = 0; v < normals.size(); ++v) EXPECT_EQ(read_normals[v], normals[v]) << v;
  EXPECT_EQ(first_face, "f 1//1 41//41 2//2");

  // A normal count that does not match the vertices is refused, and nothing is written.
  normals.pop_back();
  EXPECT_THROW(WriteMeshObj(dir + "/short.obj", mesh, normals), IoError);
  EXPECT_FALSE(std::filesystem::exists(dir + "/short.obj"));
}

TEST(MeshIo, MeshWithoutColors) {
  const std::string dir = testing::MakeTempDir("io-mesh");
  TriangleMesh mesh = MakeGridMesh();
  mesh.colors.clear();
  WriteMeshPly(dir + "/plain.ply", mesh);
  const TriangleMesh back = ReadMeshPly(dir + "/plain.ply");
  EXPECT_EQ(back.vertices.size(), mesh.vertices.size());
  EXPECT_TRUE(back.colors.empty());
}

TEST(MeshIo, MeshWithoutFacesIsAValidFile) {
  const std::string dir = testing::MakeTempDir("io-mesh");
  TriangleMesh mesh = MakeGridMesh();
  mesh.faces.clear();
  WriteMeshPly(dir + "/empty.ply", mesh);
  WriteMeshObj(dir + "/empty.obj", mesh);
  std::ifstream in(dir + "/empty.obj");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\nv 0.5 -0 3.125 0.0784"), std::string::npos) << text;
  // The reader wants triangles.
  try {
    ReadMeshPly(dir + "/empty.ply");
    FAIL();
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()), dir + "/empty.ply: mesh file holds no triangle");
  }
}

TEST(MeshIo, InvalidMeshesAreRejected) {
  const std::string dir = testing::MakeTempDir("io-mesh");
  TriangleMesh mesh = MakeGridMesh();
  mesh.faces.back()[2] = 99;
  try {
    WriteMeshPly(dir + "/bad.ply", mesh);
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.ply: mesh face 11 refers to vertex 99 of 12"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir + "/bad.ply"));
  mesh = MakeGridMesh();
  mesh.colors.pop_back();
  EXPECT_THROW(WriteMeshObj(dir + "/bad.obj", mesh), IoError);
  EXPECT_FALSE(std::filesystem::exists(dir + "/bad.obj"));
}

TEST(MeshIo, CorruptFileIsNamed) {
  const std::string dir = testing::MakeTempDir("io-mesh");
  std::ofstream(dir + "/junk.ply") << "ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n";
  try {
    ReadMeshPly(dir + "/junk.ply");
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(dir + "/junk.ply: "), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace gcpstereo::io
