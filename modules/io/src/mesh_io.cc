// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Triangle meshes. All reading goes through assimp (Assimp::Importer); both writers are written
// out here, each for a measured reason, and their tests read the files back through assimp:
//
// - Binary PLY: assimp 5.2 (Debian 12) declares vertex colours as `uchar red green blue alpha` in
//   the header of its "plyb" export but writes four float32 values per vertex, so every coloured
//   binary PLY it produces is corrupt (readers see garbage positions). The layout written below is
//   the standard one (float x y z, uchar red green blue, uchar-int face lists) that assimp, PCL,
//   MeshLab and CloudCompare read.
// - OBJ: assimp's "objnomtl" export is correct but slow. It always runs its smooth-normal step (a
//   spatial sort of every vertex) and then deduplicates positions, colours and normals through
//   std::map: 16–24 s for the 1.6 M vertices and 3 M faces of a fountain-size depth map, which
//   was the longest wait of a whole fountain run after the graph cuts. OBJ is line-based text, so
//   it is written directly with std::to_chars (9 significant digits, no locale): the same
//   `v x y z r g b` / `vn` / `f a//a b//b c//c` lines, in 2–3 s, formatted in parallel pieces.
#include "gcpstereo/io/mesh_io.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <assimp/mesh.h>
#include <assimp/scene.h>
#include <assimp/Importer.hpp>
#include <tbb/parallel_for.h>

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

// Appends a space and `value` with 9 significant digits (std::numeric_limits<float>::max_digits10,
// as assimp writes them; std::to_chars: no locale). Nine digits, not the shortest decimal that
// would read back exactly: assimp's own reader parses some shortest decimals one unit in the last
// place off (1.5 % of the face corners of a random 200 × 150 grid), and 9-digit ones exactly.
void AppendNumber(std::string* text, float value) {
  char buffer[32];
  buffer[0] = ' ';
  const std::to_chars_result result =
      std::to_chars(buffer + 1, buffer + sizeof(buffer), value, std::chars_format::general,
                    std::numeric_limits<float>::max_digits10);
  text->append(buffer, result.ptr);
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

void WriteMeshObj(const std::string& path, const TriangleMesh& mesh,
                  const std::vector<Eigen::Vector3f>& normals) {
  CheckMesh(path, mesh);
  const bool has_colors = !mesh.colors.empty();
  const bool has_normals = !normals.empty();
  if (has_normals && normals.size() != mesh.vertices.size()) {
    throw IoError(path, "mesh has " + std::to_string(mesh.vertices.size()) + " vertices but " +
                            std::to_string(normals.size()) + " normals");
  }
  for (std::size_t v = 0; v < normals.size(); ++v) {
    if (!normals[v].allFinite()) {
      throw IoError(path, "mesh normal " + std::to_string(v) + " is not finite");
    }
  }
  const std::string header =
      "# written by gcpstereo: " + std::to_string(mesh.vertices.size()) + " vertices (v x y z" +
      (has_colors ? " r g b, colours in [0, 1])" : ")") + (has_normals ? ", their normals" : "") +
      ", " + std::to_string(mesh.faces.size()) + " triangles (1-based indices)\n";
  // The lines are formatted in pieces of kPieceLines, in parallel (the text of a KITTI frame's
  // mesh is 85 MB, a fountain view's 300 MB: formatting, not the disk, is most of the time), and
  // written in order; the file's bytes do not depend on the pieces or the threads.
  constexpr std::size_t kPieceLines = 32768;
  auto pieces_of = [](std::size_t lines) { return (lines + kPieceLines - 1) / kPieceLines; };
  const std::size_t vertex_pieces = pieces_of(mesh.vertices.size());
  const std::size_t normal_pieces = pieces_of(normals.size());
  const std::size_t face_pieces = pieces_of(mesh.faces.size());
  std::vector<std::string> pieces(vertex_pieces + normal_pieces + face_pieces);
  // A colour channel is one of 256 values: its text (" 0.356862754") formatted once.
  std::vector<std::string> channel_text(has_colors ? 256 : 0);
  for (std::size_t c = 0; c < channel_text.size(); ++c) {
    AppendNumber(&channel_text[c], static_cast<float>(c) / 255.0f);
  }
  auto format_vertices = [&](std::size_t begin, std::size_t end, std::string* text) {
    // Measured on a fountain-size mesh: 73 bytes per coloured vertex line (reserved a little
    // more, so that a piece is not reallocated).
    text->reserve((end - begin) * (has_colors ? 76 : 40));
    for (std::size_t v = begin; v < end; ++v) {
      *text += 'v';
      for (int k = 0; k < 3; ++k) AppendNumber(text, mesh.vertices[v][k]);
      if (has_colors) {
        for (int k = 0; k < 3; ++k) *text += channel_text[mesh.colors[v][k]];
      }
      *text += '\n';
    }
  };
  auto format_normals = [&](std::size_t begin, std::size_t end, std::string* text) {
    text->reserve((end - begin) * 42);  // 40 bytes per normal
    for (std::size_t v = begin; v < end; ++v) {
      *text += "vn";
      for (int k = 0; k < 3; ++k) AppendNumber(text, normals[v][k]);
      *text += '\n';
    }
  };
  auto format_faces = [&](std::size_t begin, std::size_t end, std::string* text) {
    text->reserve((end - begin) * (has_normals ? 52 : 28));  // 49 bytes per face with normals
    for (std::size_t f = begin; f < end; ++f) {
      *text += 'f';
      for (int k = 0; k < 3; ++k) {
        char digits[16];
        const std::size_t length = static_cast<std::size_t>(
            std::to_chars(digits, digits + sizeof(digits), mesh.faces[f][k] + 1).ptr - digits);
        *text += ' ';
        text->append(digits, length);
        if (has_normals) {  // position//normal: a vertex's normal has the vertex's index
          *text += "//";
          text->append(digits, length);
        }
      }
      *text += '\n';
    }
  };
  tbb::parallel_for(std::size_t{0}, pieces.size(), [&](std::size_t i) {
    if (i < vertex_pieces) {
      const std::size_t begin = i * kPieceLines;
      format_vertices(begin, std::min(begin + kPieceLines, mesh.vertices.size()), &pieces[i]);
    } else if (i < vertex_pieces + normal_pieces) {
      const std::size_t begin = (i - vertex_pieces) * kPieceLines;
      format_normals(begin, std::min(begin + kPieceLines, normals.size()), &pieces[i]);
    } else {
      const std::size_t begin = (i - vertex_pieces - normal_pieces) * kPieceLines;
      format_faces(begin, std::min(begin + kPieceLines, mesh.faces.size()), &pieces[i]);
    }
  });
  WriteFileAtomically(path, [&](const std::string& temp_path) {
    std::ofstream out(temp_path, std::ios::binary | std::ios::trunc);
    if (!out) throw IoError(path, std::string("cannot open for writing: ") + std::strerror(errno));
    out.write(header.data(), static_cast<std::streamsize>(header.size()));
    for (std::string& piece : pieces) {
      out.write(piece.data(), static_cast<std::streamsize>(piece.size()));
      std::string().swap(piece);  // released as soon as it is written
    }
    out.flush();
    if (!out) throw IoError(path, "write failed (disk full?)");
  });
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
