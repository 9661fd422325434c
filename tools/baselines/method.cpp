#include "baselines/method.hpp"

#include <cmath>
#include <limits>

#include "curvestereo/triangulate.hpp"

namespace cs::baselines {

MethodResult resultFromDepth(const Rig& rig, const ImageF& radialDepth) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const Eigen::Vector3d tp = rig.tPrime();
  const BuiltCamera cam0(rig.cam0);
  MethodResult r;
  r.depth = radialDepth;
  r.warp = FlowImage(radialDepth.width, radialDepth.height, Vec2f{nan, nan});
  for (int y = 0; y < radialDepth.height; ++y)
    for (int x = 0; x < radialDepth.width; ++x) {
      const float d = radialDepth(x, y);
      if (std::isnan(d) || d <= 0) continue;
      Vec2<double> w;
      if (warpFromDepth(cam0, tp, Vec2<double>(x, y), double(d), w)) r.warp(x, y) = {float(w.x()), float(w.y())};
    }
  return r;
}

float sampleBilinear(const ImageF& img, double x, double y) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  if (!(x >= -0.5 && y >= -0.5 && x <= img.width - 0.5 && y <= img.height - 0.5)) return nan;
  int x0 = int(std::floor(x)), y0 = int(std::floor(y));
  const double fx = x - x0, fy = y - y0;
  double sum = 0, wsum = 0, best = -1;
  float nearest = nan;
  bool complete = true;
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      const double w = (i ? fx : 1 - fx) * (j ? fy : 1 - fy);
      const int xi = std::min(std::max(x0 + i, 0), img.width - 1), yj = std::min(std::max(y0 + j, 0), img.height - 1);
      const float v = img(xi, yj);
      if (w <= 0) continue;
      if (!std::isfinite(v)) {
        complete = false;
        continue;
      }
      sum += w * v;
      wsum += w;
      if (w > best) best = w, nearest = v;
    }
  if (complete && wsum > 0) return float(sum / wsum);
  return nearest;
}

double msSince(const std::chrono::steady_clock::time_point& start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace cs::baselines
