// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "gcpstereo/core/types.h"

namespace gcpstereo::io {

// Mesh files. All reading goes through assimp (Assimp::Importer); binary PLY and OBJ are written
// directly (assimp 5.2's binary PLY exporter corrupts vertex colours and its OBJ exporter takes
// 16–24 s for a fountain-size mesh, see mesh_io.cc). Vertex colours (RGB 0…255) are kept when
// mesh.colors is non-empty. Writers are atomic and throw IoError for an invalid mesh (colour count
// ≠ vertex count, a face index out of range, a non-finite vertex or normal). A mesh without faces
// is written as a valid file of bare vertices.

// Binary little-endian PLY: float x y z [uchar red green blue], faces as uchar-count int lists.
void WriteMeshPly(const std::string& path, const TriangleMesh& mesh);

// Wavefront OBJ without a material library: `v x y z` lines (with the common `r g b` extension,
// in [0, 1], when the mesh has colours), then one `vn` line per vertex when `normals` is given
// (one per vertex, e.g. mesh::VertexNormals), then `f a b c` lines (`f a//a b//b c//c` with
// normals), 1-based. Numbers have 9 significant digits, so they read back as the same floats.
void WriteMeshObj(const std::string& path, const TriangleMesh& mesh,
                  const std::vector<Eigen::Vector3f>& normals = {});

// Reads a PLY (or any format assimp reads) into one TriangleMesh: all meshes of the file are
// concatenated, vertices are kept as stored (no post-processing, so a PLY's indexed vertices come
// back in order), colours are read from the first colour set when present. Throws IoError naming
// the file with assimp's message, or when the file holds no triangle.
TriangleMesh ReadMeshPly(const std::string& path);

}  // namespace gcpstereo::io
