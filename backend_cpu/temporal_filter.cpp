// The temporal filter of a sequence: a one-state Kalman update of each pixel's inverse depth,
// gated so that a pixel whose new estimate disagrees with the carried one beyond their
// uncertainty takes the new value at once (backend.hpp temporalFilter).
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>

#include "cpu_backend.hpp"
#include "curvestereo/camera.hpp"

namespace cs::cpu {

void temporalFilter(const View& state, const View& u, const View& w, const View& prior, const View& radial,
                    const View& points, const View* confidence, const View& mask, const TemporalParams& p) {
  const BuiltCamera cam(toCamera(p.cam));
  const Eigen::Vector3d tPrime(p.tPrime[0], p.tPrime[1], p.tPrime[2]);
  parallelRows(state.height, [&](int y) {
    for (int x = 0; x < state.width; ++x) {
      state.at(x, y, 0) = -1.f;
      state.at(x, y, 1) = 0.f;
      const float rho = radial.at(x, y);
      Vec3<double> ray;
      Vec2<double> px;
      Mat23<double> J;
      if (!masked(mask, x, y) || std::isnan(rho) || !cam.unproject(Vec2<double>(x, y), ray) ||
          !cam.project(ray, px, &J))
        continue;
      const double qm = std::isinf(rho) ? 0.0 : 1.0 / double(rho);
      const double g = (J * tPrime).norm();
      const double c = std::max(double(confidence ? confidence->at(x, y) : 1.f), double(p.minConfidence));
      const double Rm = double(p.sigmaPx) * double(p.sigmaPx) / (c * c);
      const double qp = prior.at(x, y, 0);
      const double P = double(prior.at(x, y, 1)) + double(p.processPx) * double(p.processPx);
      const double innovation = g * (qm - qp);
      if (!(qp >= 0.0) || innovation * innovation > double(p.gate) * double(p.gate) * (P + Rm)) {
        state.at(x, y, 0) = float(qm);
        state.at(x, y, 1) = float(Rm);
        continue;
      }
      const double K = std::max(P / (P + Rm), 1.0 - double(p.strength));
      const double q = qp + K * (qm - qp);
      state.at(x, y, 0) = float(q);
      state.at(x, y, 1) = float((1 - K) * (1 - K) * P + K * K * Rm);
      Vec2<double> moved;
      if (p.strength == 0.f || !cam.project(ray + q * tPrime, moved)) continue;
      storeWarp(u, w, moved.x() - x, moved.y() - y, x, y);
      // The depth triangulate() would give from the new w, without a second pass.
      radial.at(x, y) = q > 0.0 ? float(1.0 / q) : std::numeric_limits<float>::infinity();
      for (int c = 0; c < 3; ++c)
        points.at(x, y, c) = q > 0.0 ? float(ray[c] / q) : std::numeric_limits<float>::quiet_NaN();
    }
  });
}

}  // namespace cs::cpu
