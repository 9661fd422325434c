// Plane-sweep initialisation: spheres of constant inverse depth around the reference
// camera, swept through the camera model (both images share it after the calibration
// warp), scored by ZNCC, chosen winner-take-all, and checked left against right.
// Geometry in double like the fields; costs in float.
#include <cmath>

#include "cpu_backend.hpp"
#include "curvestereo/camera.hpp"

namespace cs::cpu {

namespace {

constexpr float kNoSample = -1.f;  // volume value where the hypothesis cannot be sampled
constexpr float kNoCost = 2.f;     // cost where nothing scored (the worst 1 - ZNCC)
// Regularises the ZNCC of nearly flat windows (about one grey level of noise on [0, 1]).
constexpr float kFlatVariance = 1e-5f;

double planeInverseDepth(const SweepParams& p, double k) { return p.qMax * k / double(p.planes - 1); }

// Where the reference pixel's ray, on the sphere of inverse depth q, lands in the other view.
bool projectHypothesis(const Camera& cam, const Vec3<double>& ray, const double t[3], double q, Vec2<double>& px) {
  const Vec3<double> moved(ray.x() + q * t[0], ray.y() + q * t[1], ray.z() + q * t[2]);
  return cam.project(moved, px) && cam.inImage(px);
}

// 1 - ZNCC over the masked window samples whose hypothesis could be sampled.
float windowCost(const View& reference, const View& volume, const View& mask, int x, int y, int k, int radius) {
  float n = 0, s0 = 0, s1 = 0, s00 = 0, s11 = 0, s01 = 0;
  for (int dy = -radius; dy <= radius; ++dy)
    for (int dx = -radius; dx <= radius; ++dx) {
      const int sx = x + dx, sy = y + dy;
      if (!masked(mask, sx, sy)) continue;
      const float b = volume.at(sx, sy, k);
      if (b < 0.f) continue;
      const float a = reference.at(sx, sy);
      n += 1.f, s0 += a, s1 += b, s00 += a * a, s11 += b * b, s01 += a * b;
    }
  const int side = 2 * radius + 1;
  if (2.f * n < float(side * side)) return kNoCost;
  const float m0 = s0 / n, m1 = s1 / n;
  const float v0 = std::max(0.f, s00 / n - m0 * m0), v1 = std::max(0.f, s11 / n - m1 * m1);
  const float cov = s01 / n - m0 * m1;
  return 1.f - cov / std::sqrt((v0 + kFlatVariance) * (v1 + kFlatVariance));
}

// Vertex of the parabola through (-1, before), (0, best), (1, after), within half a plane.
float parabolaOffset(float before, float best, float after) {
  if (before >= kNoCost || after >= kNoCost) return 0.f;
  const float curvature = before - 2.f * best + after;
  if (!(curvature > 1e-6f)) return 0.f;
  return std::min(0.5f, std::max(-0.5f, 0.5f * (before - after) / curvature));
}

}  // namespace

void sweepWarp(const View& volume, const View& image, const View& mask, const SweepParams& p) {
  const Camera cam = toCamera(p.cam);
  parallelRows(volume.height, [&](int y) {
    for (int x = 0; x < volume.width; ++x) {
      for (int k = 0; k < p.planes; ++k) volume.at(x, y, k) = kNoSample;
      Vec3<double> ray;
      if (!masked(mask, x, y) || !cam.unproject(Vec2<double>(x, y), ray)) continue;
      for (int k = 0; k < p.planes; ++k) {
        Vec2<double> px;
        if (!projectHypothesis(cam, ray, p.t, planeInverseDepth(p, k), px)) continue;
        volume.at(x, y, k) = sampleBilinear(image, float(px.x()), float(px.y()));
      }
    }
  });
}

void sweepSelect(const View& best, const View& reference, const View& volume, const View& mask, const SweepParams& p) {
  parallelRows(best.height, [&](int y) {
    for (int x = 0; x < best.width; ++x) {
      best.at(x, y, 0) = -1.f;
      best.at(x, y, 1) = kNoCost;
      if (!masked(mask, x, y)) continue;
      int winner = -1;
      float winnerCost = kNoCost, before = kNoCost, after = kNoCost, previous = kNoCost;
      for (int k = 0; k < p.planes; ++k) {
        const float cost = windowCost(reference, volume, mask, x, y, k, p.radius);
        if (cost < winnerCost) {
          winner = k, winnerCost = cost, before = previous, after = kNoCost;
        } else if (k == winner + 1) {
          after = cost;
        }
        previous = cost;
      }
      if (winner < 0) continue;
      const double k = winner + parabolaOffset(before, winnerCost, after);
      best.at(x, y, 0) = float(std::max(0.0, planeInverseDepth(p, k)));
      best.at(x, y, 1) = winnerCost;
    }
  });
}

void sweepInitialise(const View& u, const View& w, const View& confidence, const View& best, const View& other,
                     const View& mask, const SweepParams& p, const ConsistencyParams& c) {
  const Camera cam = toCamera(p.cam);
  const double back[3] = {-p.t[0], -p.t[1], -p.t[2]};
  parallelRows(u.height, [&](int y) {
    for (int x = 0; x < u.width; ++x) {
      confidence.at(x, y) = 0.f;
      const float q = best.at(x, y, 0);
      Vec3<double> ray;
      Vec2<double> there;
      if (!masked(mask, x, y) || q < 0.f || !cam.unproject(Vec2<double>(x, y), ray) ||
          !projectHypothesis(cam, ray, p.t, q, there))
        continue;

      // Round trip: the other view's hypothesis at the nearest pixel, carried back.
      const int nx = int(std::lround(there.x())), ny = int(std::lround(there.y()));
      if (!masked(mask, nx, ny)) continue;
      const float qOther = other.at(nx, ny, 0);
      Vec3<double> rayOther;
      Vec2<double> returned;
      if (qOther < 0.f || !cam.unproject(there, rayOther) || !projectHypothesis(cam, rayOther, back, qOther, returned))
        continue;
      const double e = std::hypot(returned.x() - x, returned.y() - y) / c.tolerancePx;
      const float consistency = float(std::exp(-e * e));
      confidence.at(x, y) = consistency;
      if (consistency < c.acceptConfidence) continue;  // keep the coarse-to-fine estimate
      const double wx = there.x() - x, wy = there.y() - y;
      w.at(x, y, 0) = float(wx);
      w.at(x, y, 1) = float(wy);
      u.at(x, y) = float(std::sqrt(wx * wx + wy * wy));
    }
  });
}

}  // namespace cs::cpu
