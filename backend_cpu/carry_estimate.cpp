// A state (inverse depth and its variance) moved into the next frame's view: the warm start
// of a sequence and the temporal filter's prior (backend.hpp carryEstimate). A gather, not a
// forward splat: every output pixel looks up where its point was, so the kernel needs no
// atomics or z-buffer and gives the same result on every backend.
#include <Eigen/Core>
#include <cmath>

#include "cpu_backend.hpp"
#include "curvestereo/camera.hpp"

namespace cs::cpu {

namespace {

struct Sample {
  float q = -1.f, v = 0.f;
  Vec3<double> ray;
  bool found = false;
};

// The state at the src pixel nearest to the projection of direction d.
Sample lookUp(const View& src, const BuiltCamera& cam, const Vec3<double>& d) {
  Sample s;
  Vec2<double> px;
  if (!cam.project(d, px)) return s;
  const double nx = std::floor(px.x() + 0.5 - kCarryTie), ny = std::floor(px.y() + 0.5 - kCarryTie);
  if (!(nx >= 0 && ny >= 0 && nx < src.width && ny < src.height)) return s;
  const int ix = int(nx), iy = int(ny);
  s.q = src.at(ix, iy, 0);
  s.v = src.at(ix, iy, 1);
  s.found = s.q >= 0.f && cam.unproject(Vec2<double>(ix, iy), s.ray);
  return s;
}

}  // namespace

void carryEstimate(const View& dst, const View& src, const View* guess, const float motion[kMotionFloats],
                   const View& mask, const CarryParams& p) {
  const BuiltCamera srcCam(toCamera(p.srcCam)), dstCam(toCamera(p.dstCam));
  Eigen::Matrix3d R;
  for (int i = 0; i < 9; ++i) R(i / 3, i % 3) = motion[i];
  const Eigen::Vector3d T(motion[9] + p.extraT[0], motion[10] + p.extraT[1], motion[11] + p.extraT[2]);
  parallelRows(dst.height, [&](int y) {
    for (int x = 0; x < dst.width; ++x) {
      dst.at(x, y, 0) = -1.f;
      dst.at(x, y, 1) = 0.f;
      Vec3<double> ray;
      if (!masked(mask, x, y) || !dstCam.unproject(Vec2<double>(x, y), ray)) continue;
      double q;
      if (guess) {
        const float radial = guess->at(x, y);
        if (std::isnan(radial) || radial <= 0.f) continue;
        q = std::isinf(radial) ? 0.0 : 1.0 / double(radial);
      } else {
        const Sample s = lookUp(src, srcCam, ray);
        if (!s.found) continue;
        q = s.q;
      }
      Sample s;
      for (int k = 0; k < p.iterations; ++k) {
        s = lookUp(src, srcCam, R.transpose() * (ray - q * T));
        if (!s.found) break;
        q = double(s.q) / (R * s.ray + double(s.q) * T).norm();
      }
      if (!s.found) continue;
      dst.at(x, y, 0) = float(q);
      dst.at(x, y, 1) = s.v;
    }
  });
}

}  // namespace cs::cpu
