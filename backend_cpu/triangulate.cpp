// Depth from the warp: rays from camera 0 and from the rotation-compensated camera 1
// (core/src/triangulate.cpp holds the per-pixel maths, in double precision).
#include <Eigen/Core>
#include <cmath>
#include <limits>

#include "cpu_backend.hpp"
#include "curvestereo/triangulate.hpp"

namespace cs::cpu {

void triangulate(const View& radial, const View& points, const View& w, const View& mask, const CameraParams& cam0p,
                 const double tPrimeArray[3]) {
  const BuiltCamera cam0(toCamera(cam0p));
  const Eigen::Vector3d tPrime(tPrimeArray[0], tPrimeArray[1], tPrimeArray[2]);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  parallelRows(radial.height, [&](int y) {
    for (int x = 0; x < radial.width; ++x) {
      radial.at(x, y) = nan;
      for (int c = 0; c < 3; ++c) points.at(x, y, c) = nan;
      if (!masked(mask, x, y)) continue;
      const Vec2<double> px(x, y), wx(w.at(x, y, 0), w.at(x, y, 1));
      const double r = triangulateRadial(cam0, tPrime, px, wx);
      Vec3<double> ray;
      if (std::isnan(r) || !cam0.unproject(px, ray)) continue;
      radial.at(x, y) = float(r);
      if (!std::isfinite(r)) continue;
      for (int c = 0; c < 3; ++c) points.at(x, y, c) = float(r * ray[c]);
    }
  });
}

}  // namespace cs::cpu
