// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <memory>
#include <string>

#include <Eigen/Core>

#include "gcpstereo/core/types.h"

namespace gcpstereo::synth {

// The procedural texture families of the synthetic scene: the easy and the hard cases of stereo.
enum class TextureKind {
  kRich,    // multi-octave value noise with veins (stone): easy to match
  kWeak,    // nearly uniform plaster (±2 % low-frequency variation): ambiguous
  kBricks,  // periodic bricks with mortar joints: repetitive, ambiguous along the period
  kStripes  // periodic stripes: repetitive
};

// Where a ray meets the scene.
struct SurfaceHit {
  double t = 0.0;                // ray parameter; metres along a unit direction
  Eigen::Vector3d normal_world;  // unit surface normal, turned to face the ray's origin
  int primitive = -1;            // index of the primitive hit (see PrimitiveName)
};

// A fixed "courtyard" scene modelled on Strecha's fountain-P11, made only of analytic primitives
// whose ray intersections are exact (closed form, or bisection to 1e-9 m for the relief panel):
//   - a ground plane (rich texture), a facade wall of weak plaster with a brick plinth
//   (repetitive),
//     a protruding central section of sandstone (rich) carrying a relief panel (height field),
//     pilasters, a cornice, a slanted coping and three steps;
//   - a fountain basin: a body of revolution of a polyline profile (stacked cones and annuli)
//     with a central column and a sphere on top;
//   - two striped columns (cylinders) in front of the wall (occluders), two pedestals with balls
//     (one rich, one weak), a slanted board leaning on the wall, a railing of thin posts and a
//     thin horizontal rail (2–2.5 cm radius), a lamp post with a spherical lamp.
// World frame (metres): x to the right along the wall, y into the wall (the wall's front face is
// the plane y = 0, everything in front of it has y < 0), z up, ground at z = 0.
class AnalyticScene {
 public:
  // `texture_min_wavelength_m` band-limits the procedural textures (the finest noise octave and
  // no finer detail), to be chosen about 2–3 pixel footprints at the working distance; > 0.
  // `texture_seed` selects the noise lattice of the textures.
  static AnalyticScene MakeCourtyard(double texture_min_wavelength_m, std::uint64_t texture_seed);

  // Nearest intersection with t in (1e-6, t_max) along origin + t · direction (direction unit).
  bool Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double t_max,
                 SurfaceHit* hit) const;
  // True when anything lies on the ray with t in (1e-6, t_max) (shadow rays).
  bool Occluded(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                double t_max) const;

  // Diffuse albedo (linear RGB, each in [0, 1]) of primitive `primitive` at a surface point.
  Eigen::Vector3d Albedo(int primitive, const Eigen::Vector3d& point_world) const;

  // The exact surface of every primitive as one triangle mesh with vertex colours (the albedo).
  // Curved primitives are tessellated so that no chord deviates from the surface by more than
  // `max_chord_error_m` (vertices lie exactly on the surface; faces lie inside convex parts).
  // Flat primitives are exact. Hidden faces (a box's underside on the ground) are kept.
  TriangleMesh Tessellate(double max_chord_error_m) const;

  int NumPrimitives() const;
  const std::string& PrimitiveName(int primitive) const;
  TextureKind PrimitiveTexture(int primitive) const;

  struct Impl;

 private:
  std::shared_ptr<const Impl> impl_;
};

}  // namespace gcpstereo::synth
