// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/synth/scene.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "gcpstereo/core/error.h"
#include "random.h"

namespace gcpstereo::synth {
namespace {

using Eigen::Vector3d;
constexpr double kPi = 3.14159265358979323846;
constexpr double kTMin = 1e-6;  // metres: ignore self-intersections closer than this

struct Ray {
  Vector3d origin;
  Vector3d direction;
  Vector3d inverse_direction;
};

struct Material {
  TextureKind kind = TextureKind::kRich;
  Vector3d color_a{0.5, 0.5, 0.5};  // main colour (linear RGB)
  Vector3d color_b{0.3, 0.3, 0.3};  // second colour: noise extreme, mortar, stripe
  double scale_m = 0.5;             // base wavelength of the noise / brick width / stripe period
};

// Slab test against an axis-aligned box; returns the entry/exit interval clipped to (kTMin, t_max).
bool RayBox(const Ray& ray, const Eigen::AlignedBox3d& box, double t_max) {
  double t0 = kTMin, t1 = t_max;
  for (int i = 0; i < 3; ++i) {
    double ta = (box.min()[i] - ray.origin[i]) * ray.inverse_direction[i];
    double tb = (box.max()[i] - ray.origin[i]) * ray.inverse_direction[i];
    if (ta > tb) std::swap(ta, tb);
    // NaN (0 · inf when the origin lies on a slab plane) leaves t0/t1 untouched: conservative.
    if (ta > t0) t0 = ta;
    if (tb < t1) t1 = tb;
    if (t0 > t1) return false;
  }
  return true;
}

// Orthonormal basis (u, v) completing unit `w` to a right-handed frame.
void CompleteBasis(const Vector3d& w, Vector3d* u, Vector3d* v) {
  const Vector3d helper = std::abs(w.z()) < 0.9 ? Vector3d::UnitZ() : Vector3d::UnitX();
  *u = helper.cross(w).normalized();
  *v = w.cross(*u);
}

// Number of segments so that a circle of `radius` has chord sagitta <= tol.
int SegmentsForCircle(double radius, double tol) {
  if (radius <= tol) return 8;
  const double half_angle = std::acos(std::max(-1.0, 1.0 - tol / radius));
  return std::max(8, static_cast<int>(std::ceil(kPi / half_angle)));
}

void AddTriangle(TriangleMesh* mesh, int a, int b, int c) { mesh->faces.emplace_back(a, b, c); }
int AddVertex(TriangleMesh* mesh, const Vector3d& p) {
  mesh->vertices.push_back(p.cast<float>());
  return static_cast<int>(mesh->vertices.size()) - 1;
}

class Primitive {
 public:
  virtual ~Primitive() = default;
  // Nearest t in (kTMin, t_max) with the outward (geometric) normal there.
  virtual bool Intersect(const Ray& ray, double t_max, double* t, Vector3d* normal) const = 0;
  virtual void Tessellate(double tol, TriangleMesh* mesh) const = 0;

  std::string name;
  Material material;
  Eigen::AlignedBox3d bounds;
};

// An oriented box: centre, world_from_box rotation, half extents.
class Box : public Primitive {
 public:
  Box(const Vector3d& center, const Eigen::Matrix3d& world_from_box, const Vector3d& half)
      : center_(center), rotation_(world_from_box), half_(half) {
    bounds.setEmpty();
    for (int i = 0; i < 8; ++i) bounds.extend(Corner(i));
  }
  bool Intersect(const Ray& ray, double t_max, double* t, Vector3d* normal) const override {
    const Vector3d o = rotation_.transpose() * (ray.origin - center_);
    const Vector3d d = rotation_.transpose() * ray.direction;
    double t_near = -std::numeric_limits<double>::infinity();
    double t_far = std::numeric_limits<double>::infinity();
    int near_axis = -1, far_axis = -1;
    for (int i = 0; i < 3; ++i) {
      if (std::abs(d[i]) < 1e-15) {
        if (std::abs(o[i]) > half_[i]) return false;
        continue;
      }
      double ta = (-half_[i] - o[i]) / d[i];
      double tb = (half_[i] - o[i]) / d[i];
      if (ta > tb) std::swap(ta, tb);
      if (ta > t_near) {
        t_near = ta;
        near_axis = i;
      }
      if (tb < t_far) {
        t_far = tb;
        far_axis = i;
      }
    }
    if (t_near > t_far) return false;
    double t_hit;
    int axis;
    if (t_near > kTMin) {
      t_hit = t_near;
      axis = near_axis;
    } else if (t_far > kTMin) {  // origin inside the box
      t_hit = t_far;
      axis = far_axis;
    } else {
      return false;
    }
    if (t_hit >= t_max || axis < 0) return false;
    Vector3d n_local = Vector3d::Zero();
    const double coordinate = o[axis] + t_hit * d[axis];
    n_local[axis] = coordinate > 0.0 ? 1.0 : -1.0;
    *t = t_hit;
    *normal = rotation_ * n_local;
    return true;
  }
  void Tessellate(double, TriangleMesh* mesh) const override {
    std::array<int, 8> v;
    for (int i = 0; i < 8; ++i) v[i] = AddVertex(mesh, Corner(i));
    // Corner bit 0: +x, bit 1: +y, bit 2: +z. Faces counter-clockwise seen from outside.
    const int quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                             {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
    for (const auto& q : quads) {
      AddTriangle(mesh, v[q[0]], v[q[1]], v[q[2]]);
      AddTriangle(mesh, v[q[0]], v[q[2]], v[q[3]]);
    }
  }

 private:
  Vector3d Corner(int i) const {
    const Vector3d local((i & 1) ? half_.x() : -half_.x(), (i & 2) ? half_.y() : -half_.y(),
                         (i & 4) ? half_.z() : -half_.z());
    return center_ + rotation_ * local;
  }
  Vector3d center_;
  Eigen::Matrix3d rotation_;
  Vector3d half_;
};

// Solves a t² + b t + c = 0; returns the roots in ascending order (count 0, 1 or 2).
int SolveQuadratic(double a, double b, double c, double* r0, double* r1) {
  if (std::abs(a) < 1e-14) {
    if (std::abs(b) < 1e-14) return 0;
    *r0 = -c / b;
    return 1;
  }
  const double disc = b * b - 4.0 * a * c;
  if (disc < 0.0) return 0;
  const double s = std::sqrt(disc);
  // Numerically stable form.
  const double q = -0.5 * (b + (b >= 0.0 ? s : -s));
  double x0 = q / a;
  double x1 = q != 0.0 ? c / q : x0;
  if (x0 > x1) std::swap(x0, x1);
  *r0 = x0;
  *r1 = x1;
  return 2;
}

class Sphere : public Primitive {
 public:
  Sphere(const Vector3d& center, double radius) : center_(center), radius_(radius) {
    bounds = Eigen::AlignedBox3d(center.array() - radius, center.array() + radius);
  }
  bool Intersect(const Ray& ray, double t_max, double* t, Vector3d* normal) const override {
    const Vector3d oc = ray.origin - center_;
    double r0, r1;
    const int n = SolveQuadratic(1.0, 2.0 * oc.dot(ray.direction),
                                 oc.squaredNorm() - radius_ * radius_, &r0, &r1);
    if (n < 2) return false;
    const double t_hit = r0 > kTMin ? r0 : r1;
    if (!(t_hit > kTMin) || t_hit >= t_max) return false;
    *t = t_hit;
    *normal = (ray.origin + t_hit * ray.direction - center_) / radius_;
    return true;
  }
  void Tessellate(double tol, TriangleMesh* mesh) const override {
    const int n_lon = SegmentsForCircle(radius_, tol);
    const int n_lat = std::max(4, (n_lon + 1) / 2);
    const int top = AddVertex(mesh, center_ + Vector3d(0, 0, radius_));
    std::vector<int> prev(n_lon, top);
    for (int i = 1; i <= n_lat; ++i) {
      std::vector<int> ring(n_lon);
      if (i == n_lat) {
        const int bottom = AddVertex(mesh, center_ - Vector3d(0, 0, radius_));
        std::fill(ring.begin(), ring.end(), bottom);
      } else {
        const double theta = kPi * i / n_lat;
        for (int j = 0; j < n_lon; ++j) {
          const double phi = 2.0 * kPi * j / n_lon;
          ring[j] = AddVertex(
              mesh, center_ + radius_ * Vector3d(std::sin(theta) * std::cos(phi),
                                                 std::sin(theta) * std::sin(phi), std::cos(theta)));
        }
      }
      for (int j = 0; j < n_lon; ++j) {
        const int j1 = (j + 1) % n_lon;
        if (i > 1) AddTriangle(mesh, prev[j], ring[j], prev[j1]);
        if (i < n_lat) AddTriangle(mesh, prev[j1], ring[j], ring[j1]);
      }
      prev = ring;
    }
  }

 private:
  Vector3d center_;
  double radius_;
};

// A finite capped cylinder: base centre, unit axis, radius, length.
class Cylinder : public Primitive {
 public:
  Cylinder(const Vector3d& base, const Vector3d& axis, double radius, double length)
      : base_(base), axis_(axis.normalized()), radius_(radius), length_(length) {
    CompleteBasis(axis_, &u_, &v_);
    bounds.setEmpty();
    for (int k = 0; k < 2; ++k) {
      const Vector3d c = base_ + k * length_ * axis_;
      for (int i = 0; i < 3; ++i) {
        // Extent of a circle of `radius` perpendicular to axis along world axis i.
        const double e = radius_ * std::sqrt(std::max(0.0, 1.0 - axis_[i] * axis_[i]));
        Vector3d lo = c, hi = c;
        lo[i] -= e;
        hi[i] += e;
        bounds.extend(lo);
        bounds.extend(hi);
      }
    }
  }
  bool Intersect(const Ray& ray, double t_max, double* t, Vector3d* normal) const override {
    const Vector3d rel = ray.origin - base_;
    const Vector3d o(rel.dot(u_), rel.dot(v_), rel.dot(axis_));
    const Vector3d d(ray.direction.dot(u_), ray.direction.dot(v_), ray.direction.dot(axis_));
    double best = t_max;
    Vector3d best_n_local;
    bool found = false;
    double r0, r1;
    const int n =
        SolveQuadratic(d.x() * d.x() + d.y() * d.y(), 2.0 * (o.x() * d.x() + o.y() * d.y()),
                       o.x() * o.x() + o.y() * o.y() - radius_ * radius_, &r0, &r1);
    if (n == 2) {
      for (double root : {r0, r1}) {
        if (root > kTMin && root < best) {
          const double z = o.z() + root * d.z();
          if (z >= 0.0 && z <= length_) {
            best = root;
            best_n_local = Vector3d(o.x() + root * d.x(), o.y() + root * d.y(), 0.0) / radius_;
            found = true;
            break;
          }
        }
      }
    }
    if (std::abs(d.z()) > 1e-15) {
      for (double cap : {0.0, length_}) {
        const double root = (cap - o.z()) / d.z();
        if (root > kTMin && root < best) {
          const double x = o.x() + root * d.x(), y = o.y() + root * d.y();
          if (x * x + y * y <= radius_ * radius_) {
            best = root;
            best_n_local = Vector3d(0, 0, cap > 0.0 ? 1.0 : -1.0);
            found = true;
          }
        }
      }
    }
    if (!found) return false;
    *t = best;
    *normal = best_n_local.x() * u_ + best_n_local.y() * v_ + best_n_local.z() * axis_;
    return true;
  }
  void Tessellate(double tol, TriangleMesh* mesh) const override {
    const int n = SegmentsForCircle(radius_, tol);
    std::vector<int> bottom(n), top(n);
    for (int j = 0; j < n; ++j) {
      const double phi = 2.0 * kPi * j / n;
      const Vector3d radial = radius_ * (std::cos(phi) * u_ + std::sin(phi) * v_);
      bottom[j] = AddVertex(mesh, base_ + radial);
      top[j] = AddVertex(mesh, base_ + radial + length_ * axis_);
    }
    const int c_bottom = AddVertex(mesh, base_);
    const int c_top = AddVertex(mesh, base_ + length_ * axis_);
    for (int j = 0; j < n; ++j) {
      const int j1 = (j + 1) % n;
      AddTriangle(mesh, bottom[j], bottom[j1], top[j1]);
      AddTriangle(mesh, bottom[j], top[j1], top[j]);
      AddTriangle(mesh, c_top, top[j], top[j1]);
      AddTriangle(mesh, c_bottom, bottom[j1], bottom[j]);
    }
  }

 private:
  Vector3d base_, axis_, u_, v_;
  double radius_, length_;
};

// A body of revolution about the vertical line through (axis_x, axis_y): the profile polyline
// (r_i, z_i) is swept around the axis, each segment giving a cone frustum (or an annulus when
// z is constant, or a cylinder when r is constant). The surface is exact: no approximation of the
// profile, only the tessellation approximates the angular direction.
class Revolution : public Primitive {
 public:
  Revolution(double axis_x, double axis_y, std::vector<std::pair<double, double>> profile)
      : ax_(axis_x), ay_(axis_y), profile_(std::move(profile)) {
    double r_max = 0.0, z_min = 1e30, z_max = -1e30;
    for (const auto& [r, z] : profile_) {
      r_max = std::max(r_max, r);
      z_min = std::min(z_min, z);
      z_max = std::max(z_max, z);
    }
    r_max_ = r_max;
    bounds = Eigen::AlignedBox3d(Vector3d(ax_ - r_max, ay_ - r_max, z_min),
                                 Vector3d(ax_ + r_max, ay_ + r_max, z_max));
  }
  bool Intersect(const Ray& ray, double t_max, double* t, Vector3d* normal) const override {
    const double ox = ray.origin.x() - ax_, oy = ray.origin.y() - ay_, oz = ray.origin.z();
    const double dx = ray.direction.x(), dy = ray.direction.y(), dz = ray.direction.z();
    double best = t_max;
    bool found = false;
    Vector3d best_n;
    for (size_t i = 0; i + 1 < profile_.size(); ++i) {
      const auto [ra, za] = profile_[i];
      const auto [rb, zb] = profile_[i + 1];
      if (std::abs(zb - za) < 1e-12) {  // annulus in the plane z = za
        if (std::abs(dz) < 1e-15) continue;
        const double root = (za - oz) / dz;
        if (!(root > kTMin && root < best)) continue;
        const double x = ox + root * dx, y = oy + root * dy;
        const double r = std::sqrt(x * x + y * y);
        if (r < std::min(ra, rb) || r > std::max(ra, rb)) continue;
        best = root;
        // Profile tangent (rb − ra, 0) → normal (0, −(rb − ra)) in (r, z): up when going inwards.
        best_n = Vector3d(0, 0, rb < ra ? 1.0 : -1.0);
        found = true;
        continue;
      }
      // r(z) = ra + k (z − za); (ox + t dx)² + (oy + t dy)² = (m + n t)².
      const double k = (rb - ra) / (zb - za);
      const double m = ra + k * (oz - za), n = k * dz;
      double r0, r1;
      const int count = SolveQuadratic(dx * dx + dy * dy - n * n, 2.0 * (ox * dx + oy * dy - m * n),
                                       ox * ox + oy * oy - m * m, &r0, &r1);
      for (int c = 0; c < count; ++c) {
        const double root = c == 0 ? r0 : r1;
        if (!(root > kTMin && root < best)) continue;
        const double z = oz + root * dz;
        if (z < std::min(za, zb) || z > std::max(za, zb)) continue;
        if (m + n * root < 0.0) continue;  // the mirrored nappe of the cone
        const double x = ox + root * dx, y = oy + root * dy;
        const double rho = std::sqrt(x * x + y * y);
        const Vector3d radial = rho > 1e-12 ? Vector3d(x / rho, y / rho, 0) : Vector3d(1, 0, 0);
        // Tangent (dr, dz) = (rb − ra, zb − za); normal (dz, −dr).
        best_n = (radial * (zb - za) - Vector3d::UnitZ() * (rb - ra)).normalized();
        best = root;
        found = true;
      }
    }
    if (!found) return false;
    *t = best;
    *normal = best_n;
    return true;
  }
  void Tessellate(double tol, TriangleMesh* mesh) const override {
    const int n = SegmentsForCircle(r_max_, tol);
    std::vector<std::vector<int>> rings;
    for (const auto& [r, z] : profile_) {
      std::vector<int> ring(n);
      if (r < 1e-9) {
        std::fill(ring.begin(), ring.end(), AddVertex(mesh, Vector3d(ax_, ay_, z)));
      } else {
        for (int j = 0; j < n; ++j) {
          const double phi = 2.0 * kPi * j / n;
          ring[j] = AddVertex(mesh, Vector3d(ax_ + r * std::cos(phi), ay_ + r * std::sin(phi), z));
        }
      }
      rings.push_back(std::move(ring));
    }
    for (size_t i = 0; i + 1 < rings.size(); ++i) {
      const auto& a = rings[i];
      const auto& b = rings[i + 1];
      for (int j = 0; j < n; ++j) {
        const int j1 = (j + 1) % n;
        if (a[j] != a[j1]) AddTriangle(mesh, a[j], a[j1], b[j1]);
        if (b[j] != b[j1]) AddTriangle(mesh, a[j], b[j1], b[j]);
      }
    }
  }

 private:
  double ax_, ay_, r_max_ = 0.0;
  std::vector<std::pair<double, double>> profile_;  // (radius, z) in metres
};

// A carved relief: the rectangle origin + u e_u + v e_v (u in [0, W], v in [0, H]) displaced by
// h(u, v) ≥ 0 along e_w. h vanishes on the border, so the relief joins the wall without steps.
class ReliefPanel : public Primitive {
 public:
  ReliefPanel(const Vector3d& origin, const Vector3d& e_u, const Vector3d& e_v, double width,
              double height, double amplitude, double wavelength)
      : origin_(origin),
        e_u_(e_u.normalized()),
        e_v_(e_v.normalized()),
        e_w_(e_u.cross(e_v).normalized()),
        width_(width),
        height_(height),
        amplitude_(amplitude),
        wavelength_(wavelength) {
    bounds.setEmpty();
    for (int i = 0; i < 8; ++i) {
      bounds.extend(origin_ + ((i & 1) ? width_ : 0.0) * e_u_ + ((i & 2) ? height_ : 0.0) * e_v_ +
                    ((i & 4) ? amplitude_ : 0.0) * e_w_);
    }
    // Bound of the second derivatives (numerically, on a fine grid) for the tessellation.
    const double step = wavelength_ / 16.0, e = 1e-3;
    for (double u = e; u < width_ - e; u += step) {
      for (double v = e; v < height_ - e; v += step) {
        const double huu = (H(u + e, v) - 2 * H(u, v) + H(u - e, v)) / (e * e);
        const double hvv = (H(u, v + e) - 2 * H(u, v) + H(u, v - e)) / (e * e);
        const double huv =
            (H(u + e, v + e) - H(u + e, v - e) - H(u - e, v + e) + H(u - e, v - e)) / (4 * e * e);
        curvature_bound_ =
            std::max(curvature_bound_, std::abs(huu) + 2 * std::abs(huv) + std::abs(hvv));
        const double hu = (H(u + e, v) - H(u - e, v)) / (2 * e);
        const double hv = (H(u, v + e) - H(u, v - e)) / (2 * e);
        gradient_bound_ = std::max(gradient_bound_, std::hypot(hu, hv));
      }
    }
    gradient_bound_ *= 1.25;  // the grid samples may miss the exact maximum
  }

  // The height field: a central dome plus a periodic pattern of bosses, tapered at the border.
  double H(double u, double v) const {
    if (u <= 0.0 || v <= 0.0 || u >= width_ || v >= height_) return 0.0;
    const double margin = 0.35;
    auto taper = [margin](double s, double extent) {
      const double d = std::min(s, extent - s);
      if (d >= margin) return 1.0;
      const double x = std::sin(0.5 * kPi * d / margin);
      return x * x;
    };
    const double du = (u - 0.5 * width_) / (0.22 * width_);
    const double dv = (v - 0.55 * height_) / (0.2 * height_);
    const double dome = std::exp(-0.5 * (du * du + dv * dv));
    const double k = 2.0 * kPi / wavelength_;
    const double pattern = 0.5 + 0.5 * std::cos(k * u) * std::cos(k * v);
    return amplitude_ * taper(u, width_) * taper(v, height_) * (0.55 * dome + 0.45 * pattern);
  }

  bool Intersect(const Ray& ray, double t_max, double* t, Vector3d* normal) const override {
    const Vector3d rel = ray.origin - origin_;
    const Vector3d o(rel.dot(e_u_), rel.dot(e_v_), rel.dot(e_w_));
    const Vector3d d(ray.direction.dot(e_u_), ray.direction.dot(e_v_), ray.direction.dot(e_w_));
    // Clip the ray to the local box [0,W]×[0,H]×[0,A].
    double t0 = kTMin, t1 = t_max;
    const double lo[3] = {0.0, 0.0, 0.0}, hi[3] = {width_, height_, amplitude_};
    for (int i = 0; i < 3; ++i) {
      if (std::abs(d[i]) < 1e-15) {
        if (o[i] < lo[i] || o[i] > hi[i]) return false;
        continue;
      }
      double ta = (lo[i] - o[i]) / d[i], tb = (hi[i] - o[i]) / d[i];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    if (t0 >= t1) return false;
    auto f = [&](double s) { return o.z() + s * d.z() - H(o.x() + s * d.x(), o.y() + s * d.y()); };
    // March: a step never exceeds f / L (L bounds |df/dt|, so no root is stepped over: sphere
    // tracing) unless it moves the ray by less than wavelength/32 across the panel; then refine
    // the bracketing interval.
    const double lateral = std::hypot(d.x(), d.y());
    const double lipschitz = std::abs(d.z()) + gradient_bound_ * lateral;
    const double dt_lateral = lateral > 1e-12 ? wavelength_ / 32.0 / lateral : 1e30;
    double a = t0, fa = f(a);
    if (fa <= 0.0) return false;  // starts below the relief: hit from behind the wall
    while (a < t1) {
      const double b = std::min(a + std::max(fa / lipschitz, dt_lateral), t1);
      const double fb = f(b);
      if (fb <= 0.0) {
        // Illinois (modified regula falsi) on the bracket f(lo) > 0 >= f(hi): converges
        // superlinearly; stops when the bracket is below 1e-7 m (float depth maps resolve 1e-6 m).
        double lo_t = a, hi_t = b, f_lo = fa, f_hi = fb;
        int side = 0;
        for (int it = 0; it < 100 && hi_t - lo_t > 1e-7; ++it) {
          double mid = (lo_t * f_hi - hi_t * f_lo) / (f_hi - f_lo);
          if (!(mid > lo_t && mid < hi_t)) mid = 0.5 * (lo_t + hi_t);
          const double f_mid = f(mid);
          if (f_mid > 0.0) {
            lo_t = mid;
            f_lo = f_mid;
            if (side == -1) f_hi *= 0.5;
            side = -1;
          } else {
            hi_t = mid;
            f_hi = f_mid;
            if (side == 1) f_lo *= 0.5;
            side = 1;
          }
          if (f_mid == 0.0) lo_t = hi_t = mid;
        }
        const double th = 0.5 * (lo_t + hi_t);
        const double u = o.x() + th * d.x(), v = o.y() + th * d.y();
        const double e = 1e-6;
        const double hu = (H(u + e, v) - H(u - e, v)) / (2 * e);
        const double hv = (H(u, v + e) - H(u, v - e)) / (2 * e);
        *t = th;
        *normal = (e_w_ - hu * e_u_ - hv * e_v_).normalized();
        return true;
      }
      a = b;
      fa = fb;
    }
    return false;
  }

  void Tessellate(double tol, TriangleMesh* mesh) const override {
    // Linear interpolation error on a triangle of size h is at most h²/8 · (|huu|+2|huv|+|hvv|).
    const double h = std::sqrt(8.0 * tol / std::max(curvature_bound_, 1e-9));
    const int nu = std::max(2, static_cast<int>(std::ceil(width_ / h)));
    const int nv = std::max(2, static_cast<int>(std::ceil(height_ / h)));
    const int first = static_cast<int>(mesh->vertices.size());
    for (int j = 0; j <= nv; ++j) {
      for (int i = 0; i <= nu; ++i) {
        const double u = width_ * i / nu, v = height_ * j / nv;
        AddVertex(mesh, origin_ + u * e_u_ + v * e_v_ + H(u, v) * e_w_);
      }
    }
    auto index = [&](int i, int j) { return first + j * (nu + 1) + i; };
    for (int j = 0; j < nv; ++j) {
      for (int i = 0; i < nu; ++i) {
        AddTriangle(mesh, index(i, j), index(i + 1, j), index(i + 1, j + 1));
        AddTriangle(mesh, index(i, j), index(i + 1, j + 1), index(i, j + 1));
      }
    }
  }

 private:
  Vector3d origin_, e_u_, e_v_, e_w_;
  double width_, height_, amplitude_, wavelength_;
  double curvature_bound_ = 0.0;
  double gradient_bound_ = 0.0;  // max |∇h|, with a safety factor applied after sampling
};

// ---- procedural textures ----

double Smooth(double x) { return x * x * x * (x * (x * 6.0 - 15.0) + 10.0); }

// Lattice of value noise: a seeded permutation of 1024 entries and 1024 uniform values, so a
// lattice value costs three table look-ups (Perlin's scheme). Period: 1024 lattice cells.
struct NoiseLattice {
  static constexpr int kSize = 1024;
  std::array<std::uint16_t, kSize> perm;
  std::array<double, kSize> value;
  explicit NoiseLattice(std::uint64_t seed) {
    internal::KeyedRng rng(internal::Mix64(seed));
    for (int i = 0; i < kSize; ++i) perm[i] = static_cast<std::uint16_t>(i);
    for (int i = kSize - 1; i > 0; --i) {  // Fisher–Yates
      const int j = static_cast<int>(rng.NextU64() % static_cast<std::uint64_t>(i + 1));
      std::swap(perm[i], perm[j]);
    }
    for (int i = 0; i < kSize; ++i) value[i] = rng.Uniform();
  }
  double At(std::int64_t x, std::int64_t y, std::int64_t z, int octave) const {
    const int m = kSize - 1;
    return value[perm[(perm[(perm[(x + 331 * octave) & m] + y) & m] + z) & m]];
  }
};

// Value noise in [0, 1], C² interpolation between lattice values.
double ValueNoise(const Vector3d& p, const NoiseLattice& lattice, int octave) {
  const double fx = std::floor(p.x()), fy = std::floor(p.y()), fz = std::floor(p.z());
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy),
             iz = static_cast<std::int64_t>(fz);
  const double tx = Smooth(p.x() - fx), ty = Smooth(p.y() - fy), tz = Smooth(p.z() - fz);
  auto lerp = [](double a, double b, double t) { return a + (b - a) * t; };
  auto c = [&](int a, int b, int e) { return lattice.At(ix + a, iy + b, iz + e, octave); };
  const double x00 = lerp(c(0, 0, 0), c(1, 0, 0), tx), x10 = lerp(c(0, 1, 0), c(1, 1, 0), tx);
  const double x01 = lerp(c(0, 0, 1), c(1, 0, 1), tx), x11 = lerp(c(0, 1, 1), c(1, 1, 1), tx);
  return lerp(lerp(x00, x10, ty), lerp(x01, x11, ty), tz);
}

// Fractal sum of octaves from `base_wavelength` down to `min_wavelength` (the last octave fades
// in smoothly so the band limit has no visible seam), normalised to mean ≈ 0.5.
double Fbm(const Vector3d& p, double base_wavelength, double min_wavelength, double persistence,
           const NoiseLattice& lattice, int max_octaves = 12) {
  double sum = 0.0, norm = 0.0, amplitude = 1.0, wavelength = base_wavelength;
  for (int octave = 0; octave < max_octaves; ++octave) {
    double weight = 1.0;
    if (wavelength < min_wavelength) {
      weight = std::clamp(2.0 - min_wavelength / wavelength, 0.0, 1.0);
      if (weight <= 0.0) break;
    }
    sum += weight * amplitude * ValueNoise(p / wavelength, lattice, octave);
    norm += weight * amplitude;
    amplitude *= persistence;
    wavelength *= 0.5;
  }
  return norm > 0.0 ? sum / norm : 0.5;
}

}  // namespace

struct AnalyticScene::Impl {
  std::vector<std::unique_ptr<Primitive>> primitives;
  std::vector<NoiseLattice> lattices;  // one per primitive
  double min_wavelength_m = 0.02;
  std::uint64_t texture_seed = 0;
};

namespace {

Eigen::Matrix3d RotationAbout(const Vector3d& axis, double angle_deg) {
  return Eigen::AngleAxisd(angle_deg * kPi / 180.0, axis.normalized()).toRotationMatrix();
}

}  // namespace

AnalyticScene AnalyticScene::MakeCourtyard(double texture_min_wavelength_m,
                                           std::uint64_t texture_seed) {
  if (!(texture_min_wavelength_m > 0.0)) {
    throw Error("AnalyticScene: texture_min_wavelength_m must be > 0, got " +
                std::to_string(texture_min_wavelength_m));
  }
  auto impl = std::make_shared<Impl>();
  impl->min_wavelength_m = texture_min_wavelength_m;
  impl->texture_seed = texture_seed;
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  auto add = [&](std::unique_ptr<Primitive> p, const std::string& name, Material m) {
    p->name = name;
    p->material = m;
    impl->primitives.push_back(std::move(p));
  };
  // Box from min/max corners (axis-aligned).
  auto aabox = [&](const Vector3d& lo, const Vector3d& hi) {
    return std::make_unique<Box>(0.5 * (lo + hi), I, 0.5 * (hi - lo));
  };
  const Material gravel{TextureKind::kRich, {0.42, 0.38, 0.33}, {0.18, 0.16, 0.14}, 0.6};
  const Material plaster{TextureKind::kWeak, {0.70, 0.64, 0.55}, {0.70, 0.64, 0.55}, 2.0};
  const Material bricks{TextureKind::kBricks, {0.55, 0.27, 0.18}, {0.72, 0.70, 0.66}, 0.24};
  const Material sandstone{TextureKind::kRich, {0.78, 0.68, 0.52}, {0.42, 0.34, 0.25}, 0.8};
  const Material grey_stone{TextureKind::kRich, {0.62, 0.62, 0.60}, {0.28, 0.28, 0.30}, 0.35};
  const Material marble{TextureKind::kRich, {0.80, 0.79, 0.76}, {0.45, 0.45, 0.48}, 0.5};
  const Material stripes{TextureKind::kStripes, {0.78, 0.76, 0.70}, {0.25, 0.22, 0.20}, 0.12};
  const Material painted{TextureKind::kWeak, {0.20, 0.35, 0.55}, {0.20, 0.35, 0.55}, 1.0};
  const Material metal{TextureKind::kWeak, {0.12, 0.12, 0.13}, {0.12, 0.12, 0.13}, 1.0};
  const Material wood{TextureKind::kStripes, {0.55, 0.38, 0.22}, {0.38, 0.24, 0.13}, 0.05};

  // Ground: z = 0 (a thin slab), wide enough for every view.
  add(aabox({-25, -25, -0.1}, {25, 15, 0}), "ground", gravel);
  // Facade: weak plaster above a brick plinth, a protruding sandstone centre.
  add(aabox({-7.5, 0.0, 0.0}, {7.5, 0.8, 5.4}), "wall", plaster);
  add(aabox({-7.5, -0.04, 0.0}, {7.5, 0.8, 1.1}), "plinth", bricks);
  add(aabox({-3.0, -0.15, 0.0}, {3.0, 0.8, 6.6}), "central_section", sandstone);
  add(std::make_unique<ReliefPanel>(Vector3d(-1.9, -0.15, 2.1), Vector3d(1, 0, 0),
                                    Vector3d(0, 0, 1), 3.8, 3.4, 0.10, 0.48),
      "relief", sandstone);
  // ReliefPanel's e_w = e_u × e_v = x × z = −y: the relief comes towards the cameras.
  for (double x : {-3.3, 3.3}) {
    add(aabox({x - 0.28, -0.38, 0.0}, {x + 0.28, 0.8, 6.9}),
        x < 0 ? "pilaster_left" : "pilaster_right", grey_stone);
  }
  add(aabox({-3.8, -0.45, 6.6}, {3.8, 0.8, 6.9}), "cornice", grey_stone);
  // Slanted coping on the cornice: a slab tilted 30° back towards the wall.
  add(std::make_unique<Box>(Vector3d(0.0, 0.1, 7.15), RotationAbout(Vector3d::UnitX(), -30.0),
                            Vector3d(3.7, 0.5, 0.08)),
      "coping", grey_stone);
  // Three steps in front of the central section.
  add(aabox({-3.6, -1.5, 0.0}, {3.6, 0.0, 0.15}), "step_1", marble);
  add(aabox({-3.6, -1.1, 0.15}, {3.6, 0.0, 0.30}), "step_2", marble);
  add(aabox({-3.6, -0.7, 0.30}, {3.6, 0.0, 0.45}), "step_3", marble);
  // Fountain: a basin on a stem with a column and a ball, as one profile polyline (r, z).
  std::vector<std::pair<double, double>> profile = {{0.0, 0.0},   {0.60, 0.0},  {0.60, 0.12},
                                                    {0.42, 0.20}, {0.30, 0.32}, {0.27, 0.50},
                                                    {0.30, 0.58}};
  for (int i = 1; i <= 24; ++i) {  // quarter-ellipse underside of the bowl
    const double a = 0.5 * kPi * i / 24.0;
    profile.emplace_back(0.30 + 0.95 * std::sin(a), 0.58 + 0.37 * (1.0 - std::cos(a)));
  }
  profile.insert(profile.end(), {{1.25, 1.02},
                                 {1.17, 1.06},
                                 {1.10, 0.92},
                                 {0.16, 0.92},
                                 {0.12, 1.35},
                                 {0.16, 1.42},
                                 {0.10, 1.50},
                                 {0.0, 1.50}});
  add(std::make_unique<Revolution>(0.0, -2.9, profile), "fountain_basin", marble);
  add(std::make_unique<Sphere>(Vector3d(0.0, -2.9, 1.70), 0.21), "fountain_ball", grey_stone);
  // Two striped columns in front of the wall (occluders).
  for (double x : {-4.4, 4.4}) {
    add(std::make_unique<Cylinder>(Vector3d(x, -2.6, 0.0), Vector3d::UnitZ(), 0.22, 3.4),
        x < 0 ? "column_left" : "column_right", stripes);
  }
  // Pedestals with balls: one rich, one weak.
  add(aabox({-6.2, -1.6, 0.0}, {-5.6, -1.0, 1.0}), "pedestal_left", grey_stone);
  add(std::make_unique<Sphere>(Vector3d(-5.9, -1.3, 1.35), 0.35), "ball_left", sandstone);
  add(aabox({5.6, -1.6, 0.0}, {6.2, -1.0, 1.0}), "pedestal_right", grey_stone);
  add(std::make_unique<Sphere>(Vector3d(5.9, -1.3, 1.35), 0.35), "ball_right", painted);
  // A board leaning on the wall (slanted surface): tilted 20° about x, striped like wood.
  add(std::make_unique<Box>(Vector3d(4.7, -0.45, 1.15), RotationAbout(Vector3d::UnitX(), 20.0),
                            Vector3d(0.65, 0.025, 1.2)),
      "leaning_board", wood);
  // Railing: thin posts and a thin rail (thin structures).
  for (int i = 0; i < 7; ++i) {
    const double x = -6.6 + 0.42 * i;
    add(std::make_unique<Cylinder>(Vector3d(x, -4.2, 0.0), Vector3d::UnitZ(), 0.02, 1.0),
        "railing_post_" + std::to_string(i), metal);
  }
  add(std::make_unique<Cylinder>(Vector3d(-6.75, -4.2, 1.0), Vector3d::UnitX(), 0.025, 2.85),
      "railing_rail", metal);
  // Lamp post with a spherical lamp.
  add(std::make_unique<Cylinder>(Vector3d(2.4, -5.0, 0.0), Vector3d::UnitZ(), 0.04, 3.0),
      "lamp_post", metal);
  add(std::make_unique<Sphere>(Vector3d(2.4, -5.0, 3.15), 0.16), "lamp", marble);

  for (size_t i = 0; i < impl->primitives.size(); ++i) {
    impl->lattices.emplace_back(internal::HashKeys(texture_seed, i));
  }
  AnalyticScene scene;
  scene.impl_ = std::move(impl);
  return scene;
}

bool AnalyticScene::Intersect(const Vector3d& origin, const Vector3d& direction, double t_max,
                              SurfaceHit* hit) const {
  const Ray ray{origin, direction, direction.cwiseInverse()};
  double best = t_max;
  int best_index = -1;
  Vector3d best_normal;
  const auto& prims = impl_->primitives;
  for (size_t i = 0; i < prims.size(); ++i) {
    if (!RayBox(ray, prims[i]->bounds, best)) continue;
    double t;
    Vector3d n;
    if (prims[i]->Intersect(ray, best, &t, &n) && t < best) {
      best = t;
      best_index = static_cast<int>(i);
      best_normal = n;
    }
  }
  if (best_index < 0) return false;
  hit->t = best;
  hit->primitive = best_index;
  hit->normal_world = best_normal.dot(direction) > 0.0 ? -best_normal : best_normal;
  return true;
}

bool AnalyticScene::Occluded(const Vector3d& origin, const Vector3d& direction,
                             double t_max) const {
  const Ray ray{origin, direction, direction.cwiseInverse()};
  for (const auto& p : impl_->primitives) {
    if (!RayBox(ray, p->bounds, t_max)) continue;
    double t;
    Vector3d n;
    if (p->Intersect(ray, t_max, &t, &n)) return true;
  }
  return false;
}

Vector3d AnalyticScene::Albedo(int primitive, const Vector3d& p) const {
  const Material& m = impl_->primitives.at(primitive)->material;
  const std::uint64_t seed = internal::HashKeys(impl_->texture_seed, primitive);
  const NoiseLattice& lattice = impl_->lattices[primitive];
  const double min_wl = impl_->min_wavelength_m;
  switch (m.kind) {
    case TextureKind::kRich: {
      const double n = Fbm(p, m.scale_m, min_wl, 0.8, lattice);
      // Veins: thin bright lines where a smooth second noise crosses 0.5.
      const double vein_noise =
          Fbm(p + Vector3d(101.3, 57.9, 13.1), 1.5 * m.scale_m, min_wl, 0.5, lattice, 2);
      const double x = (vein_noise - 0.5) / 0.02;
      const double vein = std::exp(-x * x);
      const double s = std::clamp(0.5 + 3.0 * (n - 0.5), 0.0, 1.0);
      Vector3d c = m.color_b + s * (m.color_a - m.color_b);
      c *= 0.9 + 0.2 * vein;
      return c.cwiseMin(1.0);
    }
    case TextureKind::kWeak: {
      const double n = Fbm(p, m.scale_m, std::max(min_wl, 0.25 * m.scale_m), 0.5, lattice);
      return m.color_a * (1.0 + 0.04 * (n - 0.5));
    }
    case TextureKind::kBricks: {
      const double brick_w = m.scale_m, brick_h = 0.32 * m.scale_m, mortar = 0.05 * m.scale_m;
      const double u = p.x() + p.y(), v = p.z();
      const double row = std::floor(v / brick_h);
      const double shifted = u + (static_cast<std::int64_t>(row) % 2 != 0 ? 0.5 * brick_w : 0.0);
      const double col = std::floor(shifted / brick_w);
      const double fu = shifted - col * brick_w, fv = v - row * brick_h;
      if (fu < mortar || fv < mortar) return m.color_b;
      // Mild brick-to-brick variation: the pattern stays repetitive.
      const double variation = internal::ToUnit(
          internal::HashKeys(seed, static_cast<std::uint64_t>(static_cast<std::int64_t>(col)),
                             static_cast<std::uint64_t>(static_cast<std::int64_t>(row))));
      return m.color_a * (0.95 + 0.1 * variation);
    }
    case TextureKind::kStripes: {
      const double u = p.x() + p.y();
      const double s = std::sin(2.0 * kPi * u / m.scale_m);
      const double w = std::clamp(0.5 + 1.5 * s, 0.0, 1.0);
      return m.color_b + w * (m.color_a - m.color_b);
    }
  }
  return m.color_a;
}

TriangleMesh AnalyticScene::Tessellate(double max_chord_error_m) const {
  if (!(max_chord_error_m > 0.0)) {
    throw Error("AnalyticScene::Tessellate: max_chord_error_m must be > 0, got " +
                std::to_string(max_chord_error_m));
  }
  TriangleMesh mesh;
  for (size_t i = 0; i < impl_->primitives.size(); ++i) {
    const size_t first = mesh.vertices.size();
    impl_->primitives[i]->Tessellate(max_chord_error_m, &mesh);
    for (size_t v = first; v < mesh.vertices.size(); ++v) {
      const Vector3d albedo = Albedo(static_cast<int>(i), mesh.vertices[v].cast<double>());
      const Eigen::Vector3d srgb = albedo.array().pow(1.0 / 2.2) * 255.0;
      mesh.colors.emplace_back(
          static_cast<std::uint8_t>(std::lround(std::clamp(srgb.x(), 0.0, 255.0))),
          static_cast<std::uint8_t>(std::lround(std::clamp(srgb.y(), 0.0, 255.0))),
          static_cast<std::uint8_t>(std::lround(std::clamp(srgb.z(), 0.0, 255.0))));
    }
  }
  return mesh;
}

int AnalyticScene::NumPrimitives() const { return static_cast<int>(impl_->primitives.size()); }

const std::string& AnalyticScene::PrimitiveName(int primitive) const {
  return impl_->primitives.at(primitive)->name;
}

TextureKind AnalyticScene::PrimitiveTexture(int primitive) const {
  return impl_->primitives.at(primitive)->material.kind;
}

}  // namespace gcpstereo::synth
