// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
//
// A small z-buffer software rasteriser for mesh previews (see render.h). Not part of the paper.
//
// Pipeline: (1) transform every vertex once to the camera frame and project it, snapped to
// 1/256 px (fixed point); (2) bin the faces into fixed bands of rows by their bounding boxes, in
// parallel over fixed chunks of faces; a face with a vertex in front of the near plane or outside
// the guard band (the image grown by max(width, height) on every side) is first clipped against
// those planes in the camera frame (Sutherland–Hodgman) and drawn as a fan of triangles;
// (3) per band, in parallel, rasterise its triangles in mesh order into a visibility buffer
// (depth, face index) with exact 64-bit integer edge functions, the depth from the face's exact
// camera-frame plane; (4) shade each covered sample
// from the face's own vertices (barycentrics of the pixel ray's intersection with the face, which
// are perspective-correct and need no projection); (5) box-filter the supersamples. Every buffer
// element is written by exactly one band or row, and the chunk and band layouts do not depend on
// the thread count, so the output does not either.
#include "gcpstereo/mesh/render.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/system.h"
#include "gcpstereo/mesh/meshing.h"

namespace gcpstereo::mesh {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kSubpixelBits = 8;
constexpr std::int64_t kSubpixel = std::int64_t{1} << kSubpixelBits;  // fixed-point units / px
// Larger renderings are refused: with the guard band, projected coordinates then stay below
// 3 · 2^17 px, fixed-point coordinates below 2^27, and the edge functions far inside int64.
constexpr int kMaxRenderSize = 1 << 17;
// Near clipping plane: camera z, in the unit of the mesh (metres). Only keeps the projection
// finite; the guard band bounds the coordinates.
constexpr double kNearZ = 1e-6;
constexpr int kBandRows = 16;           // rows per rasterisation band
constexpr size_t kFaceChunk = 1 << 16;  // faces per binning chunk

template <typename T>
std::string Str(T value) {
  std::ostringstream stream;
  stream << value;
  return stream.str();
}

struct ProjectedVertex {
  std::int64_t x = 0;  // fixed point, 1/256 px
  std::int64_t y = 0;
};

// A vertex in the camera frame, with its projection when it lies in front of the near plane and
// inside the guard band (`inside`).
struct CameraVertex {
  Eigen::Vector3d point;
  ProjectedVertex projected;
  bool finite = false;
  bool inside = false;
};

// floor(a / kSubpixel) and ceil(a / kSubpixel) for any sign.
std::int64_t FloorDiv(std::int64_t a) {
  return a >= 0 ? a / kSubpixel : -((-a + kSubpixel - 1) / kSubpixel);
}
std::int64_t CeilDiv(std::int64_t a) { return -FloorDiv(-a); }

// Edge function of the directed edge a → b: E(p) = A·p.x + B·p.y + C, positive on the left of
// a → b in the y-down image (inside a triangle of positive area).
struct Edge {
  std::int64_t a = 0;
  std::int64_t b = 0;
  std::int64_t c = 0;
  std::int64_t bias = 0;  // 0 when samples exactly on the edge are inside, −1 otherwise

  Edge(const ProjectedVertex& from, const ProjectedVertex& to) {
    const std::int64_t dx = to.x - from.x;
    const std::int64_t dy = to.y - from.y;
    a = -dy;
    b = dx;
    c = dy * from.x - dx * from.y;
    // Tie rule: a sample p on the edge belongs to the triangle on whose side p + (ε, ε²) falls,
    // i.e. A > 0, or A = 0 and B > 0. The reversed edge (the neighbouring triangle) gets the
    // opposite answer, so shared edges and shared vertices are covered exactly once.
    bias = (a > 0 || (a == 0 && b > 0)) ? 0 : -1;
  }
  std::int64_t At(std::int64_t x, std::int64_t y) const { return a * x + b * y + c; }
};

// Twice the signed area of the screen triangle: negative = counter-clockwise as seen (front face).
std::int64_t Orient(const ProjectedVertex& v0, const ProjectedVertex& v1,
                    const ProjectedVertex& v2) {
  return (v1.x - v0.x) * (v2.y - v0.y) - (v1.y - v0.y) * (v2.x - v0.x);
}

enum class Mode { kColor, kShaded, kColorShaded };

Mode ParseMode(const std::string& mode) {
  if (mode == "color") return Mode::kColor;
  if (mode == "shaded") return Mode::kShaded;
  if (mode == "color_shaded") return Mode::kColorShaded;
  throw ConfigError(
      ViolatedConstraint("mesh.preview.mode", mode, "one of color, shaded, color_shaded"));
}

void CheckMesh(const TriangleMesh& mesh) {
  if (!mesh.colors.empty() && mesh.colors.size() != mesh.vertices.size()) {
    throw Error("RenderMesh: the mesh has " + Str(mesh.colors.size()) + " colours for " +
                Str(mesh.vertices.size()) + " vertices (expected none or one per vertex)");
  }
  const int n = static_cast<int>(mesh.vertices.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int index = mesh.faces[f][k];
      if (index < 0 || index >= n) {
        throw Error("RenderMesh: face " + Str(f) + " refers to vertex " + Str(index) +
                    " but the mesh has " + Str(n) + " vertices");
      }
    }
  }
}

// The camera-frame half-spaces l(P) >= 0 a drawn point must satisfy: in front of the near plane
// and inside the guard band [−g, width − 1 + g] × [−g, height − 1 + g], g = max(width, height).
// Each l is linear in the camera-frame point, so clipping is exact in the camera frame.
class ClipVolume {
 public:
  explicit ClipVolume(const Camera& camera) {
    const double guard = std::max(camera.width, camera.height);
    const Eigen::RowVector3d row_u = camera.K.row(0);
    const Eigen::RowVector3d row_v = camera.K.row(1);
    const Eigen::RowVector3d row_w = camera.K.row(2);
    planes_[0] = Eigen::Vector4d(0.0, 0.0, 1.0, -kNearZ);
    const double u_min = -guard, u_max = camera.width - 1 + guard;
    const double v_min = -guard, v_max = camera.height - 1 + guard;
    planes_[1] << (row_u - u_min * row_w).transpose(), 0.0;
    planes_[2] << (u_max * row_w - row_u).transpose(), 0.0;
    planes_[3] << (row_v - v_min * row_w).transpose(), 0.0;
    planes_[4] << (v_max * row_w - row_v).transpose(), 0.0;
  }

  double Value(int plane, const Eigen::Vector3d& p) const {
    return planes_[plane].head<3>().dot(p) + planes_[plane][3];
  }
  bool Inside(const Eigen::Vector3d& p) const {
    for (int k = 0; k < 5; ++k) {
      if (!(Value(k, p) >= 0.0)) return false;
    }
    return true;
  }

  // Sutherland–Hodgman: the part of the triangle inside all planes (at most 8 vertices).
  std::vector<Eigen::Vector3d> Clip(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                                    const Eigen::Vector3d& p2) const {
    std::vector<Eigen::Vector3d> polygon = {p0, p1, p2};
    std::vector<Eigen::Vector3d> next;
    for (int k = 0; k < 5 && !polygon.empty(); ++k) {
      next.clear();
      for (size_t i = 0; i < polygon.size(); ++i) {
        const Eigen::Vector3d& a = polygon[i];
        const Eigen::Vector3d& b = polygon[(i + 1) % polygon.size()];
        const double va = Value(k, a);
        const double vb = Value(k, b);
        if (va >= 0.0) next.push_back(a);
        if ((va >= 0.0) != (vb >= 0.0)) next.push_back(a + (va / (va - vb)) * (b - a));
      }
      polygon.swap(next);
    }
    return polygon;
  }

 private:
  std::array<Eigen::Vector4d, 5> planes_;
};

ProjectedVertex Project(const Camera& camera, const Eigen::Vector3d& point_camera) {
  const Eigen::Vector3d h = camera.K * point_camera;
  ProjectedVertex v;
  v.x = std::llround(h.x() / h.z() * kSubpixel);
  v.y = std::llround(h.y() / h.z() * kSubpixel);
  return v;
}

std::vector<CameraVertex> TransformVertices(const TriangleMesh& mesh, const Camera& camera,
                                            const ClipVolume& clip) {
  std::vector<CameraVertex> out(mesh.vertices.size());
  const Eigen::Matrix3d camera_from_world = camera.world_from_camera_rotation.transpose();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.vertices.size(), 4096),
                    [&](const tbb::blocked_range<size_t>& r) {
                      for (size_t i = r.begin(); i != r.end(); ++i) {
                        CameraVertex& v = out[i];
                        v.point = camera_from_world *
                                  (mesh.vertices[i].cast<double>() - camera.center_world);
                        v.finite = v.point.allFinite();
                        v.inside = v.finite && clip.Inside(v.point);
                        if (v.inside) v.projected = Project(camera, v.point);
                      }
                    });
  return out;
}

// A triangle made by clipping a face: its projected corners and the face it belongs to.
struct ClippedTriangle {
  std::array<ProjectedVertex, 3> vertices;
  int face = 0;
};

// What one chunk of faces sends to each band: entries >= 0 are faces drawn from the shared
// projected vertices, entries < 0 are clipped triangles −(entry + 1) of `clipped`.
struct Chunk {
  std::vector<std::vector<int>> bands;
  std::vector<ClippedTriangle> clipped;
  std::int64_t drawn = 0;
  std::int64_t culled = 0;
  std::int64_t skipped = 0;
  std::int64_t clipped_faces = 0;
};

struct Box {
  std::int64_t min_x, max_x, min_y, max_y;
  bool Empty() const { return min_x > max_x || min_y > max_y; }
};

// The samples (pixel centres) in the triangle's bounding box, within the image.
Box SampleBox(const ProjectedVertex& v0, const ProjectedVertex& v1, const ProjectedVertex& v2,
              int width, int height) {
  Box box;
  box.min_x = std::max<std::int64_t>(CeilDiv(std::min({v0.x, v1.x, v2.x})), 0);
  box.max_x = std::min<std::int64_t>(FloorDiv(std::max({v0.x, v1.x, v2.x})), width - 1);
  box.min_y = std::max<std::int64_t>(CeilDiv(std::min({v0.y, v1.y, v2.y})), 0);
  box.max_y = std::min<std::int64_t>(FloorDiv(std::max({v0.y, v1.y, v2.y})), height - 1);
  return box;
}

void AddToBands(const Box& box, int entry, Chunk* chunk) {
  for (std::int64_t band = box.min_y / kBandRows; band <= box.max_y / kBandRows; ++band) {
    chunk->bands[band].push_back(entry);
  }
}

// 1/z on the plane of a face is affine in the pixel coordinates: with the camera-frame plane
// n·P = n·P0 and the pixel ray d = K⁻¹ (u, v, 1) (d.z = 1), z = n·P0 / n·d, so
// 1/z = (nᵀ K⁻¹ / n·P0) (u, v, 1). Computed from the unsnapped camera-frame vertices, so the depth
// is exact whatever the snapping (and the same for every piece of a clipped face). Returns false
// for a face whose plane contains the camera centre (seen edge-on).
bool InverseDepthPlane(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                       const Eigen::Vector3d& p2, const Eigen::Matrix3d& k_inverse,
                       Eigen::RowVector3d* coefficients) {
  const Eigen::Vector3d normal = (p1 - p0).cross(p2 - p0);
  const double offset = normal.dot(p0);
  if (!(std::abs(offset) > 0.0)) return false;
  *coefficients = normal.transpose() * k_inverse / offset;
  return true;
}

// Rasterises one triangle into rows [row0, row1] of the visibility buffer, with 1/z from the
// face's plane; returns the number of samples inside it.
std::int64_t RasteriseTriangle(const ProjectedVertex& a, const ProjectedVertex& b,
                               const ProjectedVertex& c, const Eigen::RowVector3d& inverse_depth,
                               int face, int row0, int row1, cv::Mat* depth, cv::Mat* face_index) {
  const ProjectedVertex* v[3] = {&a, &b, &c};
  std::int64_t orient = Orient(*v[0], *v[1], *v[2]);
  if (orient == 0) return 0;
  if (orient < 0) std::swap(v[1], v[2]);  // positive area
  const Edge e[3] = {Edge(*v[1], *v[2]), Edge(*v[2], *v[0]), Edge(*v[0], *v[1])};
  Box box = SampleBox(*v[0], *v[1], *v[2], depth->cols, depth->rows);
  box.min_y = std::max<std::int64_t>(box.min_y, row0);
  box.max_y = std::min<std::int64_t>(box.max_y, row1);
  std::int64_t samples = 0;
  for (std::int64_t row = box.min_y; row <= box.max_y; ++row) {
    float* depth_row = depth->ptr<float>(static_cast<int>(row));
    int* face_row = face_index->ptr<int>(static_cast<int>(row));
    std::int64_t w[3];
    for (int k = 0; k < 3; ++k) w[k] = e[k].At(box.min_x * kSubpixel, row * kSubpixel);
    const double row_inverse_depth = inverse_depth[1] * static_cast<double>(row) + inverse_depth[2];
    for (std::int64_t col = box.min_x; col <= box.max_x; ++col) {
      if (w[0] + e[0].bias >= 0 && w[1] + e[1].bias >= 0 && w[2] + e[2].bias >= 0) {
        ++samples;
        const double sample_inverse_depth =
            inverse_depth[0] * static_cast<double>(col) + row_inverse_depth;
        // (≤ 0 only for a sample that snapping put just beyond the horizon of a grazing face.)
        const float z = static_cast<float>(1.0 / sample_inverse_depth);
        if (sample_inverse_depth > 0.0 && z < depth_row[col]) {
          depth_row[col] = z;
          face_row[col] = face;
        }
      }
      for (int k = 0; k < 3; ++k) w[k] += e[k].a * kSubpixel;
    }
  }
  return samples;
}

}  // namespace

void MeshRenderOptions::Check() const {
  ParseMode(mode);
  if (!(crease_angle_deg >= 0.0 && crease_angle_deg <= 180.0)) {
    throw ConfigError(ViolatedConstraint("mesh.preview.crease_angle_deg", Str(crease_angle_deg),
                                         "0 <= crease_angle_deg <= 180"));
  }
  if (!(ambient >= 0.0 && ambient <= 1.0)) {
    throw ConfigError(
        ViolatedConstraint("mesh.preview.ambient", Str(ambient), "0 <= ambient <= 1"));
  }
  if (supersampling < 1 || supersampling > 4) {
    throw ConfigError(ViolatedConstraint("mesh.preview.supersampling", Str(supersampling),
                                         "1 <= supersampling <= 4"));
  }
  if (background_grey < 0 || background_grey > 255) {
    throw ConfigError(ViolatedConstraint("mesh.preview.background_grey", Str(background_grey),
                                         "0 <= background_grey <= 255"));
  }
  if (surface_grey < 0 || surface_grey > 255) {
    throw ConfigError(ViolatedConstraint("mesh.preview.surface_grey", Str(surface_grey),
                                         "0 <= surface_grey <= 255"));
  }
}

MeshRenderResult RenderMesh(const TriangleMesh& mesh, const Camera& camera,
                            const MeshRenderOptions& options) {
  const Timer timer;
  options.Check();
  camera.Validate("RenderMesh: camera");
  CheckMesh(mesh);
  const Mode mode = ParseMode(options.mode);
  const int s = options.supersampling;
  const Camera sampling_camera = s > 1 ? camera.Rescaled(s) : camera;
  const int width = sampling_camera.width;
  const int height = sampling_camera.height;
  if (width > kMaxRenderSize || height > kMaxRenderSize) {
    throw Error("RenderMesh: " + Str(width) + "x" + Str(height) +
                " samples (camera size × supersampling) exceed the limit of " +
                Str(kMaxRenderSize) + " per side");
  }

  // (1) Camera frame and projection.
  const ClipVolume clip(sampling_camera);
  const std::vector<CameraVertex> vertices = TransformVertices(mesh, sampling_camera, clip);

  // (2) Binning into bands of rows, per fixed chunk of faces.
  const int num_bands = (height + kBandRows - 1) / kBandRows;
  const size_t num_chunks = (mesh.faces.size() + kFaceChunk - 1) / kFaceChunk;
  std::vector<Chunk> chunks(num_chunks);
  tbb::parallel_for(size_t{0}, num_chunks, [&](size_t chunk_index) {
    Chunk& chunk = chunks[chunk_index];
    chunk.bands.resize(num_bands);
    const size_t begin = chunk_index * kFaceChunk;
    const size_t end = std::min(mesh.faces.size(), begin + kFaceChunk);
    for (size_t f = begin; f < end; ++f) {
      const Eigen::Vector3i& face = mesh.faces[f];
      const CameraVertex& v0 = vertices[face[0]];
      const CameraVertex& v1 = vertices[face[1]];
      const CameraVertex& v2 = vertices[face[2]];
      if (!v0.finite || !v1.finite || !v2.finite) {
        ++chunk.skipped;
        continue;
      }
      if (v0.inside && v1.inside && v2.inside) {
        const std::int64_t orient = Orient(v0.projected, v1.projected, v2.projected);
        if (orient == 0) {
          ++chunk.skipped;
          continue;
        }
        if (options.cull_back_faces && orient > 0) {
          ++chunk.culled;
          continue;
        }
        const Box box = SampleBox(v0.projected, v1.projected, v2.projected, width, height);
        if (box.Empty()) continue;  // covers no sample of the image
        ++chunk.drawn;
        AddToBands(box, static_cast<int>(f), &chunk);
        continue;
      }
      // Clipped: front-facing when the normal points to the camera centre (the origin).
      ++chunk.clipped_faces;
      const Eigen::Vector3d normal = (v1.point - v0.point).cross(v2.point - v0.point);
      if (options.cull_back_faces && normal.dot(v0.point) >= 0.0) {
        ++chunk.culled;
        continue;
      }
      const std::vector<Eigen::Vector3d> polygon = clip.Clip(v0.point, v1.point, v2.point);
      bool drawn = false;
      for (size_t k = 1; k + 1 < polygon.size(); ++k) {
        ClippedTriangle triangle;
        triangle.vertices = {Project(sampling_camera, polygon[0]),
                             Project(sampling_camera, polygon[k]),
                             Project(sampling_camera, polygon[k + 1])};
        triangle.face = static_cast<int>(f);
        const auto& t = triangle.vertices;
        if (Orient(t[0], t[1], t[2]) == 0) continue;
        const Box box = SampleBox(t[0], t[1], t[2], width, height);
        if (box.Empty()) continue;
        drawn = true;
        AddToBands(box, -static_cast<int>(chunk.clipped.size()) - 1, &chunk);
        chunk.clipped.push_back(triangle);
      }
      if (drawn) ++chunk.drawn;
    }
  });

  // (3) Visibility buffer, per band.
  cv::Mat depth(height, width, CV_32F, cv::Scalar(std::numeric_limits<float>::infinity()));
  cv::Mat face_index(height, width, CV_32S, cv::Scalar(-1));
  std::vector<std::int64_t> band_samples(num_bands, 0);
  const Eigen::Matrix3d k_inverse = sampling_camera.K.inverse();
  tbb::parallel_for(0, num_bands, [&](int band) {
    const int row0 = band * kBandRows;
    const int row1 = std::min(height - 1, row0 + kBandRows - 1);
    std::int64_t samples = 0;
    Eigen::RowVector3d inverse_depth;
    for (const Chunk& chunk : chunks) {
      for (const int entry : chunk.bands[band]) {
        const int f = entry >= 0 ? entry : chunk.clipped[-(entry + 1)].face;
        const Eigen::Vector3i& face = mesh.faces[f];
        if (!InverseDepthPlane(vertices[face[0]].point, vertices[face[1]].point,
                               vertices[face[2]].point, k_inverse, &inverse_depth)) {
          continue;
        }
        if (entry >= 0) {
          samples += RasteriseTriangle(vertices[face[0]].projected, vertices[face[1]].projected,
                                       vertices[face[2]].projected, inverse_depth, f, row0, row1,
                                       &depth, &face_index);
        } else {
          const ClippedTriangle& t = chunk.clipped[-(entry + 1)];
          samples += RasteriseTriangle(t.vertices[0], t.vertices[1], t.vertices[2], inverse_depth,
                                       f, row0, row1, &depth, &face_index);
        }
      }
    }
    band_samples[band] = samples;
  });

  // (4) Shading.
  const bool lit = mode != Mode::kColor;
  const bool smooth = options.crease_angle_deg > 0.0;
  const double min_cos_to_face = std::cos(options.crease_angle_deg * kPi / 180.0);
  const std::vector<Eigen::Vector3f> vertex_normals =
      lit && smooth ? VertexNormals(mesh) : std::vector<Eigen::Vector3f>();
  const bool with_colors = !mesh.colors.empty() && mode != Mode::kShaded;
  const Eigen::Matrix3d& world_from_camera = sampling_camera.world_from_camera_rotation;
  const auto background = static_cast<std::uint8_t>(options.background_grey);
  cv::Mat image(height, width, CV_8UC3, cv::Scalar(background, background, background));
  tbb::parallel_for(0, height, [&](int row) {
    const int* face_row = face_index.ptr<int>(row);
    cv::Vec3b* image_row = image.ptr<cv::Vec3b>(row);
    for (int col = 0; col < width; ++col) {
      const int f = face_row[col];
      if (f < 0) continue;
      const Eigen::Vector3i& face = mesh.faces[f];
      // Barycentrics of the point where the sample's ray d meets the face:
      // b_k ∝ d · (P_{k+1} × P_{k+2}) in the camera frame (exact, perspective-correct).
      const Eigen::Vector3d ray = k_inverse * Eigen::Vector3d(col, row, 1.0);
      double b[3];
      double sum = 0.0;
      for (int k = 0; k < 3; ++k) {
        b[k] = ray.dot(vertices[face[(k + 1) % 3]].point.cross(vertices[face[(k + 2) % 3]].point));
        sum += b[k];
      }
      for (double& bk : b) bk /= sum;

      Eigen::Vector3d rgb = Eigen::Vector3d::Constant(options.surface_grey);
      if (with_colors) {
        rgb = b[0] * mesh.colors[face[0]].cast<double>() +
              b[1] * mesh.colors[face[1]].cast<double>() +
              b[2] * mesh.colors[face[2]].cast<double>();
      }
      if (lit) {
        const Eigen::Vector3d v0 = mesh.vertices[face[0]].cast<double>();
        Eigen::Vector3d normal_world = (mesh.vertices[face[1]].cast<double>() - v0)
                                           .cross(mesh.vertices[face[2]].cast<double>() - v0);
        if (smooth) {
          // Each corner takes the vertex normal unless it is more than the crease angle away
          // from the face's own normal (a sharp edge: the corner keeps the face normal).
          const Eigen::Vector3d face_normal = normal_world.normalized();
          normal_world.setZero();
          for (int k = 0; k < 3; ++k) {
            const Eigen::Vector3d vertex_normal = vertex_normals[face[k]].cast<double>();
            normal_world +=
                b[k] *
                (vertex_normal.dot(face_normal) >= min_cos_to_face ? vertex_normal : face_normal);
          }
        }
        const Eigen::Vector3d ray_world = world_from_camera * ray;
        const double denominator = normal_world.norm() * ray_world.norm();
        const double cos_angle =
            denominator > 0.0 ? std::abs(normal_world.dot(ray_world)) / denominator : 0.0;
        rgb *= options.ambient + (1.0 - options.ambient) * cos_angle;
      }
      image_row[col] = cv::Vec3b(cv::saturate_cast<std::uint8_t>(rgb.z()),
                                 cv::saturate_cast<std::uint8_t>(rgb.y()),
                                 cv::saturate_cast<std::uint8_t>(rgb.x()));
    }
  });

  // (5) Down-sampling of the supersamples.
  MeshRenderResult result;
  if (s == 1) {
    result.image = image;
    result.depth = depth;
    result.face_index = face_index;
  } else {
    cv::resize(image, result.image, cv::Size(camera.width, camera.height), 0, 0, cv::INTER_AREA);
    result.depth.create(camera.height, camera.width, CV_32F);
    result.face_index.create(camera.height, camera.width, CV_32S);
    for (int row = 0; row < camera.height; ++row) {
      for (int col = 0; col < camera.width; ++col) {
        float best_depth = std::numeric_limits<float>::infinity();
        int best_face = -1;
        for (int dy = 0; dy < s; ++dy) {
          for (int dx = 0; dx < s; ++dx) {
            const float z = depth.at<float>(row * s + dy, col * s + dx);
            if (z < best_depth) {
              best_depth = z;
              best_face = face_index.at<int>(row * s + dy, col * s + dx);
            }
          }
        }
        result.depth.at<float>(row, col) = best_depth;
        result.face_index.at<int>(row, col) = best_face;
      }
    }
  }
  for (const Chunk& chunk : chunks) {
    result.faces_drawn += chunk.drawn;
    result.faces_culled += chunk.culled;
    result.faces_skipped += chunk.skipped;
    result.faces_clipped += chunk.clipped_faces;
  }
  for (const std::int64_t samples : band_samples) result.samples_rasterised += samples;
  result.covered_pixels = cv::countNonZero(result.face_index >= 0);
  result.seconds = timer.ElapsedSeconds();
  return result;
}

cv::Mat RenderMeshPreview(const TriangleMesh& mesh, const Camera& view_camera,
                          const MeshRenderOptions& options) {
  return RenderMesh(mesh, view_camera, options).image;
}

Camera OrbitCamera(const Camera& reference, double yaw_deg, double pitch_deg,
                   const Eigen::Vector3d& pivot) {
  const Eigen::Matrix3d& r = reference.world_from_camera_rotation;
  const Eigen::Vector3d up_world = -r.col(1);
  const Eigen::Vector3d left_world = -r.col(0);
  const Eigen::Matrix3d rotation = (Eigen::AngleAxisd(yaw_deg * kPi / 180.0, up_world) *
                                    Eigen::AngleAxisd(pitch_deg * kPi / 180.0, left_world))
                                       .toRotationMatrix();
  Camera orbit = reference;
  orbit.world_from_camera_rotation = rotation * r;
  orbit.center_world = pivot + rotation * (reference.center_world - pivot);
  return orbit;
}

Eigen::Vector3d MedianVertex(const TriangleMesh& mesh) {
  if (mesh.vertices.empty()) throw Error("MedianVertex: the mesh has no vertices");
  Eigen::Vector3d median;
  std::vector<float> values(mesh.vertices.size());
  for (int axis = 0; axis < 3; ++axis) {
    for (size_t i = 0; i < values.size(); ++i) values[i] = mesh.vertices[i][axis];
    const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
    std::nth_element(values.begin(), middle, values.end());
    median[axis] = *middle;
  }
  return median;
}

}  // namespace gcpstereo::mesh
