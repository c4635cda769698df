// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>

#include "gcpstereo/core/types.h"

namespace gcpstereo::io {

// Mesh files. OBJ writing and all reading go through assimp (Assimp::Exporter / Importer); binary
// PLY is written directly (assimp 5.2's binary PLY exporter corrupts vertex colours, see
// mesh_io.cc). Vertex colours (RGB 0…255) are kept when mesh.colors is non-empty. Writers are
// atomic and throw IoError for an invalid mesh (colour count ≠ vertex count, a face index out of
// range, a non-finite vertex) or an assimp failure (with its message). A mesh without faces is
// written as a valid file of bare vertices.

// Binary little-endian PLY: float x y z [uchar red green blue], faces as uchar-count int lists.
void WriteMeshPly(const std::string& path, const TriangleMesh& mesh);

// Wavefront OBJ without a material library (assimp format id "objnomtl"); vertex colours are
// written as the common `v x y z r g b` extension (r, g, b in [0, 1]).
void WriteMeshObj(const std::string& path, const TriangleMesh& mesh);

// Reads a PLY (or any format assimp reads) into one TriangleMesh: all meshes of the file are
// concatenated, vertices are kept as stored (no post-processing, so a PLY's indexed vertices come
// back in order), colours are read from the first colour set when present. Throws IoError naming
// the file with assimp's message, or when the file holds no triangle.
TriangleMesh ReadMeshPly(const std::string& path);

}  // namespace gcpstereo::io
