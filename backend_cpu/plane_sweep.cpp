// Plane-sweep initialisation: spheres of constant inverse depth around the reference
// camera, swept through the camera model (both images share it after the calibration
// warp), scored by ZNCC, aggregated along scanlines, chosen winner-take-all, checked left
// against right, and occluded pixels given the surface beside them.
// Geometry in double like the fields; costs in float.
#include <algorithm>
#include <cmath>
#include <vector>

#include "cpu_backend.hpp"
#include "curvestereo/camera.hpp"

namespace cs::cpu {

namespace {

constexpr float kNoSample = -1.f;  // volume value where the hypothesis cannot be sampled
constexpr float kNoCost = 2.f;     // cost where nothing scored (the worst 1 - ZNCC)

double planeInverseDepth(const SweepParams& p, double k) { return p.qMax * k / double(p.planes - 1); }

// Where the reference pixel's ray, on the sphere of inverse depth q, lands in the other view.
bool projectHypothesis(const BuiltCamera& cam, const Vec3<double>& ray, const double t[3], double q, Vec2<double>& px) {
  const Vec3<double> moved(ray.x() + q * t[0], ray.y() + q * t[1], ray.z() + q * t[2]);
  return cam.project(moved, px) && cam.inImage(px);
}

// 1 - ZNCC over the masked window samples whose hypothesis could be sampled (sample(sx, sy)
// >= 0). The sums are taken column by column (dx outer; each column's partials summed over
// dy, then added into the window's sums in dx order): GPUs walk x keeping the last 2r+1
// column partials in registers, so each output needs one new column instead of a whole
// window, and every backend sums in this order to match bit for bit.
template <class Sample>
float windowCost(const View& reference, const View& mask, int x, int y, int radius, float flatVariance,
                 const Sample& sample) {
  float n = 0, s0 = 0, s1 = 0, s00 = 0, s11 = 0, s01 = 0;
  for (int dx = -radius; dx <= radius; ++dx) {
    float cn = 0, c0 = 0, c1 = 0, c00 = 0, c11 = 0, c01 = 0;
    for (int dy = -radius; dy <= radius; ++dy) {
      const int sx = x + dx, sy = y + dy;
      if (!masked(mask, sx, sy)) continue;
      const float b = sample(sx, sy);
      if (b < 0.f) continue;
      const float a = reference.at(sx, sy);
      cn += 1.f, c0 += a, c1 += b, c00 += a * a, c11 += b * b, c01 += a * b;
    }
    n += cn, s0 += c0, s1 += c1, s00 += c00, s11 += c11, s01 += c01;
  }
  const int side = 2 * radius + 1;
  if (2.f * n < float(side * side)) return kNoCost;
  const float m0 = s0 / n, m1 = s1 / n;
  const float v0 = std::max(0.f, s00 / n - m0 * m0), v1 = std::max(0.f, s11 / n - m1 * m1);
  const float cov = s01 / n - m0 * m1;
  return 1.f - cov / std::sqrt((v0 + flatVariance) * (v1 + flatVariance));
}

// Vertex of the parabola through (-1, before), (0, best), (1, after), within half a plane.
float parabolaOffset(float before, float best, float after) {
  if (before >= kNoCost || after >= kNoCost) return 0.f;
  const float curvature = before - 2.f * best + after;
  if (!(curvature > 1e-6f)) return 0.f;
  return std::min(0.5f, std::max(-0.5f, 0.5f * (before - after) / curvature));
}

}  // namespace

namespace {

// The volume's channels at (x, y): channel k is `image` where the pixel sees hypothesis
// start + k, kNoSample where that cannot be sampled, all kNoSample for start -1.
void warpPixel(const View& volume, const View& image, const BuiltCamera& cam, const SweepParams& p, int x, int y,
               int start) {
  for (int k = 0; k < volume.channels; ++k) volume.at(x, y, k) = kNoSample;
  Vec3<double> ray;
  if (start < 0 || !cam.unproject(Vec2<double>(x, y), ray)) return;
  for (int k = 0; k < volume.channels; ++k) {
    Vec2<double> px;
    if (!projectHypothesis(cam, ray, p.t, planeInverseDepth(p, start + k), px)) continue;
    volume.at(x, y, k) = sampleBilinear(image, float(px.x()), float(px.y()));
  }
}

}  // namespace

void sweepWarp(const View& volume, const View& image, const View& mask, const SweepParams& p) {
  const BuiltCamera cam(toCamera(p.cam));
  parallelRows(volume.height, [&](int y) {
    for (int x = 0; x < volume.width; ++x) warpPixel(volume, image, cam, p, x, y, masked(mask, x, y) ? 0 : -1);
  });
}

void sweepCost(const View& costs, const View& reference, const View& volume, const View& mask, const SweepParams& p) {
  parallelRows(costs.height, [&](int y) {
    for (int x = 0; x < costs.width; ++x) {
      const bool inside = masked(mask, x, y);
      for (int k = 0; k < p.planes; ++k)
        costs.at(x, y, k) = inside ? windowCost(reference, mask, x, y, p.radius, p.flatVariance,
                                                [&](int sx, int sy) { return volume.at(sx, sy, k); })
                                   : kNoCost;
    }
  });
}

namespace {

// A cost above 1 (anticorrelated windows) says no more than "no match": capping it keeps
// one bad window from outweighing the paths' agreement.
constexpr float kCostCap = 1.f;

// The hypotheses a pixel holds: channel k is hypothesis first(x, y) + k; a full sweep's
// pixels all start at 0, a band sweep's where `first` says (-1: none).
struct Bands {
  const View* first = nullptr;  // none: the full sweep
  int at(int x, int y) const { return first ? int(first->at(x, y)) : 0; }
};

// One scanline direction (dx, dy) of the aggregation, added into `aggregated`: the lines
// along it are independent, each walked from its first pixel with the previous pixel's
// path costs in `previous`, shifted by the difference of the two pixels' bands.
void aggregateDirection(const View& aggregated, const View& costs, const View& mask, const Bands& bands, float p1,
                        float p2, int dx, int dy) {
  const bool alongRows = dy == 0;
  const int lines = alongRows ? costs.height : costs.width, length = alongRows ? costs.width : costs.height;
  const int n = costs.channels;
  parallelRows(lines, [&](int line) {
    std::vector<float> previous(static_cast<size_t>(n)), current(static_cast<size_t>(n));
    bool havePrevious = false;
    float previousMin = 0.f;
    int previousFirst = 0;
    for (int step = 0; step < length; ++step) {
      const int along = (dx + dy) > 0 ? step : length - 1 - step;
      const int x = alongRows ? along : line, y = alongRows ? line : along;
      const int first = bands.at(x, y);
      if (!masked(mask, x, y) || first < 0) {
        havePrevious = false;
        continue;
      }
      const int shift = first - previousFirst;  // channel k here is channel k + shift there
      auto held = [&](int j) { return j >= 0 && j < n; };
      float lowest = 0.f;
      for (int k = 0; k < n; ++k) {
        const float c = std::min(costs.at(x, y, k), kCostCap);
        float l = c;
        if (havePrevious) {
          const int j = k + shift;
          float v = previousMin + p2;
          if (held(j)) v = std::min(previous[size_t(j)], v);
          if (held(j - 1)) v = std::min(v, previous[size_t(j - 1)] + p1);
          if (held(j + 1)) v = std::min(v, previous[size_t(j + 1)] + p1);
          l = c + v - previousMin;
        }
        current[size_t(k)] = l;
        lowest = k == 0 ? l : std::min(lowest, l);
        aggregated.at(x, y, k) += l;
      }
      std::swap(previous, current);
      previousMin = lowest;
      previousFirst = first;
      havePrevious = true;
    }
  });
}

void aggregate(const View& aggregated, const View& costs, const View& mask, const Bands& bands, const SweepParams& p) {
  std::fill(aggregated.data, aggregated.data + size_t(aggregated.width) * aggregated.height * aggregated.channels, 0.f);
  const int directions[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  for (const auto& d : directions) aggregateDirection(aggregated, costs, mask, bands, p.p1, p.p2, d[0], d[1]);
}

// Winner-take-all over each pixel's hypotheses, refined by a parabola. In a band sweep a
// winner on an inner edge of the band (one the full range continues past) is refused.
void select(const View& best, const View& aggregated, const View& costs, const View& mask, const Bands& bands,
            const SweepParams& p) {
  constexpr float kPaths = 4.f;
  const int n = costs.channels;
  parallelRows(best.height, [&](int y) {
    for (int x = 0; x < best.width; ++x) {
      best.at(x, y, 0) = -1.f;
      best.at(x, y, 1) = kNoCost;
      const int first = bands.at(x, y);
      if (!masked(mask, x, y) || first < 0) continue;
      int winner = -1;
      for (int k = 0; k < n; ++k)
        if (costs.at(x, y, k) < kNoCost && (winner < 0 || aggregated.at(x, y, k) < aggregated.at(x, y, winner)))
          winner = k;
      if (winner < 0) continue;
      if ((winner == 0 && first > 0) || (winner == n - 1 && first + n < p.planes)) continue;
      // The parabola sees the aggregated cost per path, on the scale of one window's cost.
      auto score = [&](int k) {
        return k < 0 || k >= n || costs.at(x, y, k) >= kNoCost ? kNoCost : aggregated.at(x, y, k) / kPaths;
      };
      const double k = first + winner + parabolaOffset(score(winner - 1), score(winner), score(winner + 1));
      best.at(x, y, 0) = float(std::max(0.0, planeInverseDepth(p, k)));
      best.at(x, y, 1) = costs.at(x, y, winner);
    }
  });
}

}  // namespace

void sweepAggregate(const View& aggregated, const View& costs, const View& mask, const SweepParams& p) {
  aggregate(aggregated, costs, mask, Bands{}, p);
}

void sweepSelect(const View& best, const View& aggregated, const View& costs, const View& mask, const SweepParams& p) {
  select(best, aggregated, costs, mask, Bands{}, p);
}

// --- the band sweep ---

namespace {

// A coarse winner q as a plane index n, rounded half up (double); -1 for none (q < 0).
int coarsePlane(const View& coarseBest, int cx, int cy, const SweepParams& p) {
  const float q = coarseBest.at(cx, cy, 0);
  return q < 0.f ? -1 : int(std::floor(double(q) * double(p.planes - 1) / p.qMax + 0.5));
}

// The band of pixel (x, y): centred on the winners of the coarse 3x3 neighbourhood around
// its coarse pixel when they fit in it with kBandMargin to spare each side (at a depth edge
// the nearest coarse pixel may lie on the other surface: the band then holds both),
// otherwise on the nearest coarse pixel's winner. -1 where the pixel is not masked or the
// nearest coarse pixel has no winner.
int bandFirst(const View& coarseBest, const View& mask, const SweepParams& p, float coarseScale, int x, int y) {
  const int cx = std::min(coarseBest.width - 1, int((float(x) + 0.5f) * coarseScale));
  const int cy = std::min(coarseBest.height - 1, int((float(y) + 0.5f) * coarseScale));
  const int nearest = coarsePlane(coarseBest, cx, cy, p);
  if (!masked(mask, x, y) || nearest < 0) return -1;
  int lo = nearest, hi = nearest;
  for (int ny = std::max(cy - 1, 0); ny <= std::min(cy + 1, coarseBest.height - 1); ++ny)
    for (int nx = std::max(cx - 1, 0); nx <= std::min(cx + 1, coarseBest.width - 1); ++nx) {
      const int n = coarsePlane(coarseBest, nx, ny, p);
      if (n >= 0) lo = std::min(lo, n), hi = std::max(hi, n);
    }
  const int centre = hi - lo + 2 * kBandMargin <= p.band ? (lo + hi + 1) / 2 : nearest;
  return std::min(std::max(centre - p.band / 2, 0), p.planes - p.band);
}

}  // namespace

void sweepBandWarp(const View& volume, const View& first, const View& image, const View& coarseBest, const View& mask,
                   const SweepParams& p, float coarseScale) {
  const BuiltCamera cam(toCamera(p.cam));
  parallelRows(volume.height, [&](int y) {
    for (int x = 0; x < volume.width; ++x) {
      const int start = bandFirst(coarseBest, mask, p, coarseScale, x, y);
      first.at(x, y) = float(start);
      warpPixel(volume, image, cam, p, x, y, start);
    }
  });
}

void sweepBandCost(const View& costs, const View& reference, const View& volume, const View& first, const View& mask,
                   const SweepParams& p) {
  parallelRows(costs.height, [&](int y) {
    for (int x = 0; x < costs.width; ++x) {
      const int start = int(first.at(x, y));
      const bool inside = masked(mask, x, y) && start >= 0;
      for (int k = 0; k < p.band; ++k) {
        auto sample = [&](int sx, int sy) {
          const int there = int(first.at(sx, sy)), j = start + k - there;
          return there >= 0 && j >= 0 && j < p.band ? volume.at(sx, sy, j) : kNoSample;
        };
        costs.at(x, y, k) = inside ? windowCost(reference, mask, x, y, p.radius, p.flatVariance, sample) : kNoCost;
      }
    }
  });
}

void sweepBandAggregate(const View& aggregated, const View& costs, const View& first, const View& mask,
                        const SweepParams& p) {
  aggregate(aggregated, costs, mask, Bands{&first}, p);
}

void sweepBandSelect(const View& best, const View& aggregated, const View& costs, const View& first, const View& mask,
                     const SweepParams& p) {
  select(best, aggregated, costs, mask, Bands{&first}, p);
}

namespace {

// The left-right round trip of one pixel's sweep hypothesis: where it lands in the other
// view (there), the other view's hypothesis at the nearest pixel carried back, and the
// consistency exp(-(e / tolerance)^2) of the return error e. evaluated is false where
// the pixel has no hypothesis or its match leaves the other view's valid pixels.
struct RoundTrip {
  bool evaluated = false;
  float consistency = 0.f;
  Vec3<double> ray;
  Vec2<double> there;
};

RoundTrip roundTrip(const BuiltCamera& cam, const View& best, const View& other, const View& mask, const SweepParams& p,
                    const ConsistencyParams& c, int x, int y) {
  RoundTrip r;
  const float q = best.at(x, y, 0);
  if (!masked(mask, x, y) || q < 0.f || !cam.unproject(Vec2<double>(x, y), r.ray) ||
      !projectHypothesis(cam, r.ray, p.t, q, r.there))
    return r;
  const int nx = int(std::lround(r.there.x())), ny = int(std::lround(r.there.y()));
  if (!masked(mask, nx, ny)) return r;
  const float qOther = other.at(nx, ny, 0);
  const double back[3] = {-p.t[0], -p.t[1], -p.t[2]};
  Vec3<double> rayOther;
  Vec2<double> returned;
  if (qOther < 0.f || !cam.unproject(r.there, rayOther) || !projectHypothesis(cam, rayOther, back, qOther, returned))
    return r;
  const double e = std::hypot(returned.x() - x, returned.y() - y) / c.tolerancePx;
  r.evaluated = true;
  r.consistency = best.at(x, y, 1) > c.maxCost ? 0.f : float(std::exp(-e * e));
  return r;
}

// The sweep's hypothesis q at the ray as the warp (u, w).
bool setWarp(const View& u, const View& w, const BuiltCamera& cam, const SweepParams& p, const Vec3<double>& ray,
             double q, int x, int y) {
  Vec2<double> there;
  if (!projectHypothesis(cam, ray, p.t, q, there)) return false;
  storeWarp(u, w, there.x() - x, there.y() - y, x, y);
  return true;
}

// Occlusion: a pixel the other view cannot see is covered there by a nearer surface lying
// behind it along its epipolar curve (on the side its match moves away from: the nearer
// surface moves further and overtakes it), so the pixel belongs to the farther surface
// ahead of it. One-pixel steps along the curve's direction at the pixel (the image motion
// of growing inverse depth, J t) find the nearest consistent pixel on each side, up to
// `reach`. When the one behind is nearer (larger q) than the one ahead, the pixel takes
// the one ahead's inverse depth; -1 otherwise (or when a side has none).
double occludedSurface(const BuiltCamera& cam, const View& best, const View& confidence, const View& mask,
                       const SweepParams& p, float accept, const Vec3<double>& ray, int x, int y, int reach) {
  Vec2<double> px;
  Mat23<double> J;
  if (!cam.project(ray, px, &J)) return -1.0;
  Vec2<double> d = J * Vec3<double>(p.t[0], p.t[1], p.t[2]);
  const double norm = d.norm();
  if (!(norm > 0.0)) return -1.0;
  d /= norm;
  double nearest[2] = {-1.0, -1.0};  // behind, ahead
  for (int side = 0; side < 2; ++side) {
    const double sign = side == 0 ? -1.0 : 1.0;
    for (int s = 1; s <= reach; ++s) {
      const int nx = int(std::lround(x + sign * s * d.x())), ny = int(std::lround(y + sign * s * d.y()));
      if (!masked(mask, nx, ny)) break;
      if (confidence.at(nx, ny) < accept) continue;
      nearest[side] = best.at(nx, ny, 0);
      break;
    }
  }
  return nearest[1] >= 0.0 && nearest[0] > nearest[1] ? nearest[1] : -1.0;
}

}  // namespace

void sweepInitialise(const View& u, const View& w, const View& confidence, const View& best, const View& other,
                     const View& mask, const SweepParams& p, const ConsistencyParams& c) {
  const BuiltCamera cam(toCamera(p.cam));
  // Pass 1: confidence everywhere; consistent pixels take the sweep's hypothesis.
  parallelRows(u.height, [&](int y) {
    for (int x = 0; x < u.width; ++x) {
      const RoundTrip r = roundTrip(cam, best, other, mask, p, c, x, y);
      confidence.at(x, y) = r.consistency;
      if (r.evaluated && r.consistency >= c.acceptConfidence) setWarp(u, w, cam, p, r.ray, best.at(x, y, 0), x, y);
    }
  });
  // Pass 2: inconsistent pixels whose match stays in view and that lie in front of a
  // nearer surface take the surface ahead of them (occlusions); the rest (no hypothesis,
  // a match leaving the other view, or no occlusion) keep the coarse-to-fine estimate.
  // An occluded band is at most as wide as the largest motion, about `planes` level px.
  parallelRows(u.height, [&](int y) {
    for (int x = 0; x < u.width; ++x) {
      if (confidence.at(x, y) >= c.acceptConfidence) continue;
      const RoundTrip r = roundTrip(cam, best, other, mask, p, c, x, y);
      if (!r.evaluated) continue;
      const double q = occludedSurface(cam, best, confidence, mask, p, c.acceptConfidence, r.ray, x, y, p.planes);
      if (q >= 0.0) setWarp(u, w, cam, p, r.ray, q, x, y);
    }
  });
}

}  // namespace cs::cpu
