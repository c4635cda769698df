// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Triangle meshes. OBJ export and all reading go through assimp: the TriangleMesh becomes a
// one-mesh aiScene that Assimp::Exporter serialises to a memory blob, which is then written
// atomically (exporting straight to a file would name side files after the ".partial" path).
//
// Deliberate deviation: binary PLY is written here directly, not with assimp's "plyb" exporter.
// assimp 5.2 (Debian 12) declares vertex colours as `uchar red green blue alpha` in the header
// but writes four float32 values per vertex, so every coloured binary PLY it produces is corrupt
// (readers see garbage positions). The layout written below is the standard one (float x y z,
// uchar red green blue, uchar-int face lists) that assimp, PCL, MeshLab and CloudCompare read;
// the test reads it back through assimp.
#include "gcpstereo/io/mesh_io.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <locale>
#include <memory>
#include <sstream>
#include <string>

#include <assimp/material.h>
#include <assimp/mesh.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/io/atomic_file.h"
#include "little_endian.h"

namespace gcpstereo::io {
namespace {

void CheckMesh(const std::string& path, const TriangleMesh& mesh) {
  if (!mesh.colors.empty() && mesh.colors.size() != mesh.vertices.size()) {
    throw IoError(path, "mesh has " + std::to_string(mesh.vertices.size()) + " vertices but " +
                            std::to_string(mesh.colors.size()) + " colours");
  }
  const int num_vertices = static_cast<int>(mesh.vertices.size());
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int index = mesh.faces[f][k];
      if (index < 0 || index >= num_vertices) {
        throw IoError(path, "mesh face " + std::to_string(f) + " refers to vertex " +
                                std::to_string(index) + " of " + std::to_string(num_vertices));
      }
    }
  }
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    if (!mesh.vertices[v].allFinite()) {
      throw IoError(path, "mesh vertex " + std::to_string(v) + " is not finite");
    }
  }
}

// A scene with one root node owning one mesh and one default material.
std::unique_ptr<aiScene> MakeScene(const TriangleMesh& mesh) {
  auto scene = std::make_unique<aiScene>();
  scene->mRootNode = new aiNode();
  scene->mMaterials = new aiMaterial*[1];
  scene->mMaterials[0] = new aiMaterial();
  scene->mNumMaterials = 1;

  auto* out = new aiMesh();
  scene->mMeshes = new aiMesh*[1];
  scene->mMeshes[0] = out;
  scene->mNumMeshes = 1;
  scene->mRootNode->mMeshes = new unsigned int[1];
  scene->mRootNode->mMeshes[0] = 0;
  scene->mRootNode->mNumMeshes = 1;

  out->mMaterialIndex = 0;
  out->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  out->mNumVertices = static_cast<unsigned int>(mesh.vertices.size());
  out->mVertices = new aiVector3D[out->mNumVertices];
  for (unsigned int v = 0; v < out->mNumVertices; ++v) {
    const Eigen::Vector3f& p = mesh.vertices[v];
    out->mVertices[v] = aiVector3D(p.x(), p.y(), p.z());
  }
  if (!mesh.colors.empty()) {
    out->mColors[0] = new aiColor4D[out->mNumVertices];
    for (unsigned int v = 0; v < out->mNumVertices; ++v) {
      const auto& c = mesh.colors[v];
      out->mColors[0][v] = aiColor4D(c[0] / 255.0f, c[1] / 255.0f, c[2] / 255.0f, 1.0f);
    }
  }
  out->mNumFaces = static_cast<unsigned int>(mesh.faces.size());
  out->mFaces = new aiFace[out->mNumFaces];
  for (unsigned int f = 0; f < out->mNumFaces; ++f) {
    aiFace& face = out->mFaces[f];
    face.mNumIndices = 3;
    face.mIndices = new unsigned int[3];
    for (int k = 0; k < 3; ++k) face.mIndices[k] = static_cast<unsigned int>(mesh.faces[f][k]);
  }
  return scene;
}

void ExportMesh(const std::string& path, const TriangleMesh& mesh, const char* format_id) {
  CheckMesh(path, mesh);
  const std::unique_ptr<aiScene> scene = MakeScene(mesh);
  Assimp::Exporter exporter;
  const aiExportDataBlob* blob = exporter.ExportToBlob(scene.get(), format_id);
  if (blob == nullptr) {
    throw IoError(path, std::string("assimp export (") + format_id +
                            ") failed: " + exporter.GetErrorString());
  }
  WriteBytesAtomically(path, blob->data, blob->size);
}

std::uint8_t ToByte(float unit_value) {
  const float clamped = std::min(1.0f, std::max(0.0f, unit_value));
  return static_cast<std::uint8_t>(std::lround(clamped * 255.0f));
}

}  // namespace

void WriteMeshPly(const std::string& path, const TriangleMesh& mesh) {
  using internal::AppendLittleEndian;
  CheckMesh(path, mesh);
  const bool has_colors = !mesh.colors.empty();
  std::string bytes = "ply\nformat binary_little_endian 1.0\ncomment written by gcpstereo\n";
  bytes += "element vertex " + std::to_string(mesh.vertices.size()) + "\n";
  bytes += "property float x\nproperty float y\nproperty float z\n";
  if (has_colors) bytes += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  bytes += "element face " + std::to_string(mesh.faces.size()) + "\n";
  bytes += "property list uchar int vertex_indices\nend_header\n";
  bytes.reserve(bytes.size() + mesh.vertices.size() * (has_colors ? 15 : 12) +
                mesh.faces.size() * 13);
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    for (int k = 0; k < 3; ++k) AppendLittleEndian(&bytes, mesh.vertices[v][k]);
    if (has_colors) {
      for (int k = 0; k < 3; ++k) AppendLittleEndian(&bytes, mesh.colors[v][k]);
    }
  }
  for (const Eigen::Vector3i& face : mesh.faces) {
    AppendLittleEndian(&bytes, static_cast<std::uint8_t>(3));
    for (int k = 0; k < 3; ++k) AppendLittleEndian(&bytes, static_cast<std::int32_t>(face[k]));
  }
  WriteBytesAtomically(path, bytes.data(), bytes.size());
}

void WriteMeshObj(const std::string& path, const TriangleMesh& mesh) {
  if (mesh.faces.empty()) {
    // assimp refuses scenes without faces; an OBJ of bare vertices is still a valid file (an
    // all-invalid depth map gives an empty mesh, which is a result, not an I/O error).
    CheckMesh(path, mesh);
    std::ostringstream out;
    out.imbue(std::locale::classic());
    out << "# gcpstereo: mesh without faces\n";
    for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
      const Eigen::Vector3f& p = mesh.vertices[v];
      out << "v " << p.x() << ' ' << p.y() << ' ' << p.z();
      if (!mesh.colors.empty()) {
        for (int k = 0; k < 3; ++k) out << ' ' << mesh.colors[v][k] / 255.0;
      }
      out << '\n';
    }
    const std::string text = out.str();
    WriteBytesAtomically(path, text.data(), text.size());
    return;
  }
  ExportMesh(path, mesh, "objnomtl");
}

TriangleMesh ReadMeshPly(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw IoError(path, "mesh file not found");
  Assimp::Importer importer;
  // No post-processing except dropping lines/points: vertices stay as stored.
  const aiScene* scene = importer.ReadFile(path, 0);
  if (scene == nullptr) {
    throw IoError(path, std::string("cannot read mesh: ") + importer.GetErrorString());
  }
  TriangleMesh mesh;
  bool any_colors = false;
  for (unsigned int m = 0; m < scene->mNumMeshes; ++m) {
    any_colors = any_colors || scene->mMeshes[m]->HasVertexColors(0);
  }
  for (unsigned int m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* in = scene->mMeshes[m];
    const int base = static_cast<int>(mesh.vertices.size());
    for (unsigned int v = 0; v < in->mNumVertices; ++v) {
      const aiVector3D& p = in->mVertices[v];
      mesh.vertices.emplace_back(p.x, p.y, p.z);
      if (any_colors) {
        Eigen::Matrix<std::uint8_t, 3, 1> c(0, 0, 0);
        if (in->HasVertexColors(0)) {
          const aiColor4D& a = in->mColors[0][v];
          c << ToByte(a.r), ToByte(a.g), ToByte(a.b);
        }
        mesh.colors.push_back(c);
      }
    }
    for (unsigned int f = 0; f < in->mNumFaces; ++f) {
      const aiFace& face = in->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines are not part of a TriangleMesh
      mesh.faces.emplace_back(base + static_cast<int>(face.mIndices[0]),
                              base + static_cast<int>(face.mIndices[1]),
                              base + static_cast<int>(face.mIndices[2]));
    }
  }
  if (mesh.faces.empty()) throw IoError(path, "mesh file holds no triangle");
  return mesh;
}

}  // namespace gcpstereo::io
