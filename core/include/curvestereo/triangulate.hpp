// From the 2-D warp w to depth, and back (for ground truth and baselines).
#pragma once
#include <Eigen/Core>

#include "curvestereo/camera.hpp"
#include "curvestereo/image.hpp"

namespace cs {

struct Point3f {
  float x = 0.f, y = 0.f, z = 0.f;
};

struct DepthMaps {
  ImageF radial;          // |X| in metres; NaN where invalid; +inf where the rays do not converge
  ImageF z;               // z coordinate of X
  Image<Point3f> points;  // X in camera-0 coordinates (NaN where invalid or infinite)
};

// Radial depth of the point seen at pixel x of camera 0 and at x + w in the
// rotation-compensated second camera (cam0's model, centre at -tPrime). +inf when the
// rays do not converge in front of camera 0; NaN when x or x + w do not unproject.
double triangulateRadial(const BuiltCamera& cam0, const Eigen::Vector3d& tPrime, const Vec2<double>& x,
                         const Vec2<double>& w);

// The warp of pixel x whose point lies at radial depth `radial` (may be +inf):
// w = pi0(radial * pi0^-1(x) + tPrime) - x. False when it does not project.
bool warpFromDepth(const BuiltCamera& cam0, const Eigen::Vector3d& tPrime, const Vec2<double>& x, double radial,
                   Vec2<double>& w);

DepthMaps triangulate(const Camera& cam0, const Eigen::Vector3d& tPrime, const FlowImage& w, const ImageU8& valid);

}  // namespace cs
