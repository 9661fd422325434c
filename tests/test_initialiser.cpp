// The plane-sweep initialiser (issue: large displacements). First the oracle's kernels
// against direct computations through cs::Camera on a synthetic sphere scene, then the
// data-term weighting, then end to end on rendered pairs: a near object ~100 px away is
// recovered with the initialiser and lost without it, and the confidence it reports.
#include <algorithm>
#include <cmath>
#include <vector>

#include "cpu_backend.hpp"
#include "curvestereo/camera.hpp"
#include "curvestereo/metrics.hpp"
#include "curvestereo/pipeline_params.hpp"
#include "curvestereo/stereo.hpp"
#include "golden_cases.hpp"  // hash01
#include "synth/scene.hpp"
#include "test_util.hpp"

using namespace cs;

namespace {

struct Grid {
  int w, h, c;
  std::vector<float> data;
  Grid(int w_, int h_, int c_, float v = 0.f) : w(w_), h(h_), c(c_), data(size_t(w_) * h_ * c_, v) {}
  cpu::View view() { return cpu::View{data.data(), w, h, c}; }
  float& at(int x, int y, int ch = 0) { return data[(size_t(y) * w + x) * c + ch]; }
};

// A double-sphere lens (Usenko et al.'s model) with realistic distortion, ~190 deg over
// an odd-sized 97x81 image; every pixel unprojects.
Camera lens() { return Camera::doubleSphere(97, 81, 29.0, 29.2, 48.3, 40.1, -0.21, 0.59); }

// Bilinear sample clamped to the image edge, written independently of the oracle's.
float bilinear(Grid& g, double x, double y) {
  x = std::clamp(x, 0.0, double(g.w - 1));
  y = std::clamp(y, 0.0, double(g.h - 1));
  const int x0 = std::min(int(x), g.w - 2), y0 = std::min(int(y), g.h - 2);
  const double fx = x - x0, fy = y - y0;
  return float((g.at(x0, y0) * (1 - fx) + g.at(x0 + 1, y0) * fx) * (1 - fy) +
               (g.at(x0, y0 + 1) * (1 - fx) + g.at(x0 + 1, y0 + 1) * fx) * fy);
}

// Where pixel (x, y) sees inverse depth q in the other view: project(unproject(x) + q t),
// inside the image; false otherwise.
bool landing(const BuiltCamera& cam, const double t[3], double x, double y, double q, Vec2<double>& px) {
  Vec3<double> ray;
  if (!cam.unproject(Vec2<double>(x, y), ray)) return false;
  return cam.project(Vec3<double>(ray.x() + q * t[0], ray.y() + q * t[1], ray.z() + q * t[2]), px) && cam.inImage(px);
}

SweepParams sweepParams(const Camera& cam, const double t[3], double qMax, int planes, int radius) {
  SweepParams p{};
  p.cam = toCameraParams(cam);
  std::copy(t, t + 3, p.t);
  p.qMax = qMax;
  p.planes = planes;
  p.radius = radius;
  p.p1 = 0.05f;
  p.p2 = 0.5f;
  p.flatVariance = 1e-4f;
  return p;
}

// The pipeline's choice of hypothesis: window costs, aggregation, selection.
void select(Grid& best, Grid& reference, Grid& volume, Grid& mask, const SweepParams& p) {
  Grid costs(volume.w, volume.h, p.planes), aggregated(volume.w, volume.h, p.planes);
  cpu::sweepCost(costs.view(), reference.view(), volume.view(), mask.view(), p);
  cpu::sweepAggregate(aggregated.view(), costs.view(), mask.view(), p);
  cpu::sweepSelect(best.view(), aggregated.view(), costs.view(), mask.view(), p);
}

// A textured sphere of radius 1/qStar around the reference centre, seen from the
// reference and from the other centre at -t (a point X of the reference is X + t there):
// brightness is a function of the direction of the surface point from the reference
// centre, with detail of a few pixels.
struct SpherePair {
  Grid left, right;
};

float sphereTexture(const Vec3<double>& p) {
  const Vec3<double> u = p.normalized();
  return float(0.5 + 0.15 * std::sin(40 * u.x() + 7 * u.y()) + 0.15 * std::sin(31 * u.y() - 23 * u.z() + 1) +
               0.1 * std::sin(27 * u.x() + 35 * u.z() + 2));
}

SpherePair renderSphere(const BuiltCamera& cam, const double t[3], double qStar) {
  const int width = cam.camera().width, height = cam.camera().height;
  SpherePair pair{Grid(width, height, 1), Grid(width, height, 1)};
  const Vec3<double> T(t[0], t[1], t[2]);
  const double radius = 1.0 / qStar;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      Vec3<double> d;
      if (!cam.unproject(Vec2<double>(x, y), d)) continue;
      pair.left.at(x, y) = sphereTexture(d);
      // The other camera's ray -t + s d meets |P| = radius (the centre -t is inside).
      const double b = d.dot(T), s = b + std::sqrt(b * b - T.squaredNorm() + radius * radius);
      pair.right.at(x, y) = sphereTexture(-T + s * d);
    }
  return pair;
}

}  // namespace

TEST_CASE("sweepWarp samples image(project(ray + q_k t)) for q_k = qMax k / (planes - 1); -1 elsewhere") {
  const Camera cam = lens();
  const BuiltCamera built(cam);
  const double t[3] = {-0.12, 0.01, 0.03};
  const SweepParams p = sweepParams(cam, t, 6.0, 7, 2);
  Grid image(cam.width, cam.height, 1), mask(cam.width, cam.height, 1, 1.f), volume(cam.width, cam.height, p.planes);
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x)
      image.at(x, y) = 0.5f + 0.3f * std::sin(0.31f * x + 0.1f * y) * std::cos(0.23f * y - 0.05f * x);
  for (int y = 0; y < cam.height; ++y) mask.at(30, y) = 0.f;  // an excluded column
  cpu::sweepWarp(volume.view(), image.view(), mask.view(), p);

  long long sampled = 0, offImage = 0, excluded = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x)
      for (int k = 0; k < p.planes; ++k) {
        CAPTURE(x);
        CAPTURE(y);
        CAPTURE(k);
        const float v = volume.at(x, y, k);
        Vec2<double> px;
        if (mask.at(x, y) == 0.f) {
          ++excluded;
          CHECK(v == -1.f);
        } else if (!landing(built, t, x, y, p.qMax * k / (p.planes - 1), px)) {
          ++offImage;
          CHECK(v == -1.f);
        } else {
          ++sampled;
          CHECK(std::abs(v - bilinear(image, px.x(), px.y())) <= 1e-5f);
        }
      }
  // Both branches are exercised: the near planes leave the image on the left and at the back.
  CHECK(offImage > 1000);
  CHECK(sampled > 20000);
  CHECK(excluded == cam.height * p.planes);
}

TEST_CASE("cost, aggregation and selection recover the inverse depth of a textured sphere to a fraction of a plane") {
  const Camera cam = lens();
  const BuiltCamera built(cam);
  const double t[3] = {-0.12, 0.005, 0.01};
  // ~1.1 px of motion per plane at the centre; the true sphere lies between planes.
  const SweepParams p = sweepParams(cam, t, 2.4, 9, 3);
  const double spacing = p.qMax / (p.planes - 1);
  for (const double planeStar : {2.35, 5.7}) {
    CAPTURE(planeStar);
    const double qStar = planeStar * spacing;
    SpherePair pair = renderSphere(built, t, qStar);
    Grid mask(cam.width, cam.height, 1, 1.f), volume(cam.width, cam.height, p.planes), best(cam.width, cam.height, 2);
    cpu::sweepWarp(volume.view(), pair.right.view(), mask.view(), p);
    select(best, pair.left, volume, mask, p);
    std::vector<double> errors;
    long long scored = 0;
    for (int y = 0; y < cam.height; ++y)
      for (int x = 0; x < cam.width; ++x) {
        const float q = best.at(x, y, 0), cost = best.at(x, y, 1);
        if (q < 0.f) {
          CHECK(cost == 2.f);  // nothing scored: (-1, 2)
          continue;
        }
        ++scored;
        CHECK(cost >= 0.f);
        CHECK(cost <= 2.f);
        CHECK(q <= p.qMax + 1e-6);
        errors.push_back(std::abs(q - qStar) / spacing);
      }
    std::sort(errors.begin(), errors.end());
    const double median = errors[errors.size() / 2], p90 = errors[errors.size() * 9 / 10];
    MESSAGE("plane " << planeStar << ": " << scored << " scored, |q - q*| median " << median << ", 90th percentile "
                     << p90 << " planes");
    CHECK(scored > cam.width * cam.height * 8 / 10);
    // Measured: median 0.04 / 0.04, 90th percentile 0.12 / 0.14 planes. A sweep that
    // picked the nearest plane without the parabola would sit at 0.35 / 0.3.
    CHECK(median < 0.15);
    CHECK(p90 < 0.3);
  }
}

// The band kernels in the pipeline's order, from a coarse sweep's answer at half resolution.
void selectInBand(Grid& best, Grid& reference, Grid& image, Grid& coarseBest, Grid& mask, const SweepParams& p) {
  Grid volume(image.w, image.h, p.band), first(image.w, image.h, 1), costs(image.w, image.h, p.band),
      aggregated(image.w, image.h, p.band);
  cpu::sweepBandWarp(volume.view(), first.view(), image.view(), coarseBest.view(), mask.view(), p, 0.5f);
  cpu::sweepBandCost(costs.view(), reference.view(), volume.view(), first.view(), mask.view(), p);
  cpu::sweepBandAggregate(aggregated.view(), costs.view(), first.view(), mask.view(), p);
  cpu::sweepBandSelect(best.view(), aggregated.view(), costs.view(), first.view(), mask.view(), p);
}

TEST_CASE("the band sweep refines a coarse proposal a few planes off, and refuses one its band cannot reach") {
  const Camera cam = lens();
  const BuiltCamera built(cam);
  const double t[3] = {-0.12, 0.005, 0.01};
  // The sphere test's spacing over 40 planes; bands of 8 around the coarse proposal.
  SweepParams p = sweepParams(cam, t, 2.4 * 39.0 / 8.0, 40, 3);
  p.band = 8;
  const double spacing = p.qMax / (p.planes - 1), planeStar = 12.35, qStar = planeStar * spacing;
  SpherePair pair = renderSphere(built, t, qStar);
  Grid mask(cam.width, cam.height, 1, 1.f), best(cam.width, cam.height, 2);
  for (const double offset : {2.6, -1.8, 9.4}) {
    CAPTURE(offset);
    Grid coarse((cam.width + 1) / 2, (cam.height + 1) / 2, 2, float((planeStar + offset) * spacing));
    selectInBand(best, pair.left, pair.right, coarse, mask, p);
    std::vector<double> errors;
    long long refused = 0;
    for (int y = 0; y < cam.height; ++y)
      for (int x = 0; x < cam.width; ++x) {
        const float q = best.at(x, y, 0);
        if (q < 0.f)
          ++refused;
        else
          errors.push_back(std::abs(q - qStar) / spacing);
      }
    const long long pixels = (long long)cam.width * cam.height;
    if (std::abs(offset) > p.band) {
      // The truth lies beyond the band: where the costs fall towards it the winner sits on
      // the band's edge and is refused (measured: 51 % of the pixels; the rest find a
      // local minimum inside, which the left-right check is there to catch). Without the
      // refusal none would be.
      MESSAGE("band from " << offset << " planes off: " << refused << " of " << pixels << " refused");
      CHECK(refused > pixels * 3 / 10);
      continue;
    }
    std::sort(errors.begin(), errors.end());
    REQUIRE(errors.size() > size_t(pixels * 8 / 10));
    const double median = errors[errors.size() / 2], p90 = errors[errors.size() * 9 / 10];
    MESSAGE("band from " << offset << " planes off: " << refused << " refused, |q - q*| median " << median
                         << ", 90th percentile " << p90 << " planes");
    // As the full sweep's test: a fraction of a plane wherever the band holds the truth.
    CHECK(median < 0.15);
    CHECK(p90 < 0.3);
  }
}

TEST_CASE("beside a coarse depth edge a band holds both sides' winners where they fit, else the nearest's") {
  const Camera cam = lens();
  const double t[3] = {-0.12, 0.005, 0.01};
  SweepParams p = sweepParams(cam, t, 2.0, 40, 2);
  p.band = 12;
  const double spacing = p.qMax / (p.planes - 1);
  const int cw = (cam.width + 1) / 2, ch = (cam.height + 1) / 2, edge = cw / 2;
  Grid image(cam.width, cam.height, 1, 0.5f), mask(cam.width, cam.height, 1, 1.f);
  Grid volume(cam.width, cam.height, p.band), first(cam.width, cam.height, 1);
  for (const int far : {16, 30}) {  // 6 planes apart fit in 12 with 2 to spare each side; 20 do not
    CAPTURE(far);
    Grid coarse(cw, ch, 2);
    for (int y = 0; y < ch; ++y)
      for (int x = 0; x < cw; ++x) coarse.at(x, y, 0) = float((x < edge ? 10 : far) * spacing);
    cpu::sweepBandWarp(volume.view(), first.view(), image.view(), coarse.view(), mask.view(), p, 0.5f);
    for (int x = 0; x < cam.width; ++x) {
      const int cx = x / 2, own = cx < edge ? 10 : far, start = int(first.at(x, cam.height / 2));
      CAPTURE(x);
      if ((cx == edge - 1 || cx == edge) && far == 16) {  // a coarse neighbour across the edge
        CHECK(start <= 10);
        CHECK(start + p.band - 1 >= far);
      } else {
        CHECK(start == own - p.band / 2);
      }
    }
  }
}

TEST_CASE("sweepAggregate carries a clear minimum into windows that say nothing, and keeps depth edges sharp") {
  const int w = 40, h = 30, planes = 9;
  const double t[3] = {-0.12, 0.005, 0.01};
  const SweepParams p = sweepParams(lens(), t, 2.4, planes, 2);
  // A valley at plane 3 left of x = 30 and at plane 6 from there on; a stripe of flat
  // (ambiguous) costs at x in [17, 23); pixel (5, 5) cut off from its four neighbours.
  Grid costs(w, h, planes), mask(w, h, 1, 1.f), aggregated(w, h, planes), best(w, h, 2);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int k = 0; k < planes; ++k) {
        const double d = k - (x < 30 ? 3 : 6);
        costs.at(x, y, k) = x >= 17 && x < 23 ? 0.5f : float(std::min(1.9, 0.1 + 0.1 * d * d));
      }
  costs.at(5, 5, 0) = 1.7f;
  for (const auto& n : {std::pair{4, 5}, {6, 5}, {5, 4}, {5, 6}}) mask.at(n.first, n.second) = 0.f;
  cpu::sweepAggregate(aggregated.view(), costs.view(), mask.view(), p);
  cpu::sweepSelect(best.view(), aggregated.view(), costs.view(), mask.view(), p);
  auto plane = [&](int x, int y) { return best.at(x, y, 0) * (planes - 1) / p.qMax; };
  // Every path restarts at the isolated pixel: four times its capped cost.
  CHECK(aggregated.at(5, 5, 0) == 4.f);
  CHECK(aggregated.at(5, 5, 3) == 4.f * costs.at(5, 5, 3));
  CHECK(aggregated.at(4, 5, 3) == 0.f);  // unmasked
  long long stripe = 0, stripeRight = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 17; x < 23; ++x) stripe += std::abs(plane(x, y) - 3.0) < 0.5;
    CHECK(std::abs(plane(29, y) - 3.0) < 0.5);  // the edge stays where the costs put it
    CHECK(std::abs(plane(30, y) - 6.0) < 0.5);
    stripeRight += std::abs(plane(35, y) - 6.0) < 0.5;
  }
  // Without the paths the flat stripe would take the first plane (its first minimum).
  CHECK(stripe == 6 * h);
  CHECK(stripeRight == h);
}

TEST_CASE("sweepInitialise: w = project(ray + q t) - x where the round trip agrees; confidence 0 where it cannot") {
  const Camera cam = lens();
  const BuiltCamera built(cam);
  const double t[3] = {-0.12, 0.005, 0.01}, back[3] = {0.12, -0.005, -0.01};
  const SweepParams p = sweepParams(cam, t, 2.4, 9, 3);
  SweepParams reverse = p;
  std::copy(back, back + 3, reverse.t);
  const double qStar = 4.4 * p.qMax / (p.planes - 1);
  SpherePair pair = renderSphere(built, t, qStar);
  const int w = cam.width, h = cam.height;
  Grid mask(w, h, 1, 1.f), volume(w, h, p.planes), best(w, h, 2), other(w, h, 2);
  for (int y = 0; y < h; ++y) mask.at(60, y) = 0.f;
  cpu::sweepWarp(volume.view(), pair.right.view(), mask.view(), p);
  select(best, pair.left, volume, mask, p);
  cpu::sweepWarp(volume.view(), pair.left.view(), mask.view(), reverse);
  select(other, pair.right, volume, mask, reverse);

  // Sabotage: no reference hypothesis in one block; the other view far off in another
  // region (rows 60.. of the other image).
  for (int y = 10; y < 20; ++y)
    for (int x = 40; x < 50; ++x) best.at(x, y, 0) = -1.f;
  for (int y = 60; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (other.at(x, y, 0) >= 0.f) other.at(x, y, 0) += 1.2f;

  // The other view's true inverse depth of the point reference pixel (x, y) sees.
  auto otherInverseDepth = [&](int x, int y) {
    Vec3<double> ray;
    built.unproject(Vec2<double>(x, y), ray);
    return 1.0 / (ray / qStar + Vec3<double>(t[0], t[1], t[2])).norm();
  };
  ConsistencyParams c{};
  c.tolerancePx = 1.f;
  c.acceptConfidence = 0.5f;
  c.maxCost = 2.f;
  // The coarse-to-fine estimate the sweep may replace.
  const float keptU = -5.f;
  Grid u(w, h, 1, keptU), warp(w, h, 2), confidence(w, h, 1, 9.f), start(w, h, 2);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) start.at(x, y, 0) = -6.f, start.at(x, y, 1) = -7.f;
  warp.data = start.data;
  cpu::sweepInitialise(u.view(), warp.view(), confidence.view(), best.view(), other.view(), mask.view(), p, c);

  // Whether (x, y)'s warp is where the inverse depth of a consistent pixel within reach
  // (p.planes px) takes it.
  auto fromConsistentNeighbour = [&](int x, int y) {
    for (int ny = std::max(0, y - p.planes); ny <= std::min(h - 1, y + p.planes); ++ny)
      for (int nx = std::max(0, x - p.planes); nx <= std::min(w - 1, x + p.planes); ++nx) {
        Vec2<double> there;
        if (confidence.at(nx, ny) < c.acceptConfidence || !landing(built, t, x, y, best.at(nx, ny, 0), there)) continue;
        if (std::abs(warp.at(x, y, 0) - (there.x() - x)) < 1e-4 && std::abs(warp.at(x, y, 1) - (there.y() - y)) < 1e-4)
          return true;
      }
    return false;
  };
  long long consistent = 0, consistentConfident = 0, disagreeing = 0, replaced = 0, filled = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      CAPTURE(x);
      CAPTURE(y);
      const float conf = confidence.at(x, y), q = best.at(x, y, 0);
      CHECK(conf >= 0.f);
      CHECK(conf <= 1.f);
      const bool kept =
          u.at(x, y) == keptU && warp.at(x, y, 0) == start.at(x, y, 0) && warp.at(x, y, 1) == start.at(x, y, 1);
      if (mask.at(x, y) == 0.f || q < 0.f) {
        CHECK(conf == 0.f);
        CHECK(kept);
        continue;
      }
      // Replaced by the sweep's w where the confidence reaches acceptConfidence; below it
      // kept, or (an occlusion) set to the inverse depth of a consistent pixel nearby.
      Vec2<double> there;
      REQUIRE(landing(built, t, x, y, q, there));
      if (conf >= c.acceptConfidence) {
        ++replaced;
        CHECK(warp.at(x, y, 0) == doctest::Approx(there.x() - x).epsilon(1e-5));
        CHECK(warp.at(x, y, 1) == doctest::Approx(there.y() - y).epsilon(1e-5));
      } else if (!kept) {
        ++filled;
        CHECK(fromConsistentNeighbour(x, y));
      }
      if (!kept) CHECK(u.at(x, y) == doctest::Approx(std::hypot(warp.at(x, y, 0), warp.at(x, y, 1))).epsilon(1e-6));
      const int nx = int(std::lround(there.x())), ny = int(std::lround(there.y()));
      if (nx < 2 || ny < 2 || nx >= w - 2 || ny >= h - 2 || mask.at(nx, ny) == 0.f) continue;
      if (ny >= 60) {
        ++disagreeing;
        CHECK(conf < 0.02f);  // the other view is 1.2 /m (~4 planes, px) off
      } else if (std::abs(q - qStar) < 0.1 && std::abs(other.at(nx, ny, 0) - otherInverseDepth(x, y)) < 0.1) {
        ++consistent;  // both sweeps within a third of a plane of the truth
        consistentConfident += conf > 0.6f;
      }
    }
  MESSAGE(consistent << " consistent pixels, " << consistentConfident << " of them with confidence > 0.6; "
                     << disagreeing << " disagreeing; " << replaced << " replaced; " << filled
                     << " inconsistent ones filled from a neighbour");
  CHECK(disagreeing > 300);
  CHECK(replaced > 2000);
  CHECK(consistent > 2000);
  // Measured: all 5191 consistent pixels above 0.6.
  CHECK(consistentConfident >= 0.9 * consistent);
}

TEST_CASE("warpDerivatives with a confidence buffer scales iz and iu by max(confidence, floor)") {
  const int w = 31, h = 23;
  Grid i0(w, h, 1), i1(w, h, 1), traj(w, h, 2), warp(w, h, 2), u(w, h, 1), mask(w, h, 1, 1.f), conf(w, h, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const uint32_t i = uint32_t(y * w + x);
      i0.at(x, y) = 0.5f + 0.4f * std::sin(0.5f * x + 0.3f * y);
      i1.at(x, y) = 0.5f + 0.4f * std::sin(0.5f * x + 0.3f * y - 0.7f);
      traj.at(x, y, 0) = 1.f, traj.at(x, y, 1) = 0.2f;
      warp.at(x, y, 0) = 2.f * golden::hash01(i * 3 + 1) - 1.f;
      warp.at(x, y, 1) = 2.f * golden::hash01(i * 3 + 2) - 1.f;
      u.at(x, y) = golden::hash01(i * 3 + 3);
      conf.at(x, y) = i % 5 == 0 ? 0.f : golden::hash01(i * 7 + 4);
    }
  conf.at(5, 5) = 1.f;
  const float floor = 0.25f;
  Grid u0a(w, h, 1), iua(w, h, 1), iza(w, h, 1), ga(w, h, 2), u0b(w, h, 1), iub(w, h, 1), izb(w, h, 1), gb(w, h, 2);
  cpu::warpDerivatives(u0a.view(), iua.view(), iza.view(), ga.view(), i0.view(), i1.view(), traj.view(), warp.view(),
                       u.view(), mask.view(), nullptr, floor);
  const cpu::View confView = conf.view();
  cpu::warpDerivatives(u0b.view(), iub.view(), izb.view(), gb.view(), i0.view(), i1.view(), traj.view(), warp.view(),
                       u.view(), mask.view(), &confView, floor);
  CHECK(u0a.data == u0b.data);
  CHECK(ga.data == gb.data);
  long long below = 0, above = 0, nonZero = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float weight = std::max(conf.at(x, y), floor);
      (conf.at(x, y) < floor ? below : above) += 1;
      nonZero += iza.at(x, y) != 0.f;
      CHECK(izb.at(x, y) == doctest::Approx(weight * iza.at(x, y)).epsilon(1e-6));
      CHECK(iub.at(x, y) == doctest::Approx(weight * iua.at(x, y)).epsilon(1e-6));
    }
  CHECK(below > 100);
  CHECK(above > 100);
  CHECK(nonZero > w * h / 2);
}

// ---------------------------------------------------------------- end to end

namespace {

// A rendered pair whose nearest object (a box, "near0", 0.5 m away on a 0.35 m baseline)
// moves ~100 px: beyond what coarse-to-fine warping reaches from zero on this pyramid
// (3 levels of 256 px: 30 warps x 0.2 px x (1 + 2 + 4) = 42 px). A 256x256 lens of f =
// 150 px (an equidistant fisheye cropped to ~100 deg, T265-like distortion) keeps the
// CPU solves to a few seconds.
struct NearScene {
  synth::SynthPair pair;
  FlowImage truth;
  ImageU8 nonOccluded, nearObject;  // nearObject: non-occluded pixels of near0 with a true warp
  DepthResult plain, initialised;   // preset "variational" and "quality"
  DepthResult banded;               // preset "realtime": the band sweep (Release only)
};

// Per-pixel end-point error statistics over a mask.
struct Accuracy {
  double tau1 = 0, epe = 0, medianTruth = 0;  // tau1 in percent
  long long pixels = 0;
};

Accuracy accuracyOn(const NearScene& s, const DepthResult& r, const ImageU8& where) {
  Accuracy a;
  long long bad = 0;
  std::vector<double> truth;
  for (int y = 0; y < where.height; ++y)
    for (int x = 0; x < where.width; ++x) {
      if (!where(x, y)) continue;
      ++a.pixels;
      const Vec2f gt = s.truth(x, y), est = r.warp(x, y);
      const double e = std::hypot(double(est.x) - gt.x, double(est.y) - gt.y);
      bad += !(e <= 1.0);
      a.epe += std::isfinite(e) ? e : 1e3;
      truth.push_back(std::hypot(gt.x, gt.y));
    }
  if (a.pixels == 0) return a;
  std::sort(truth.begin(), truth.end());
  a.tau1 = 100.0 * bad / a.pixels;
  a.epe /= a.pixels;
  a.medianTruth = truth[truth.size() / 2];
  return a;
}

// Under the sanitizers the near scene is solved with 5 warps a level instead of 30 (the
// three solves took over 5 minutes of the sanitizer stage), rendered with one sample per
// pixel instead of 2x2, and not solved with the band sweep: there only the confidence case
// runs, on the plain and the initialised solve (the depth truth and the occlusion masks
// come from the pixel-centre rays either way), and the band sweep's result is used only
// by an accuracy bound (test_pipeline and test_robustness run that preset there).
Params nearPreset(const std::string& name) {
  Params p = preset(name);
  p.warps = test::shortUnderSanitizers(p.warps);
  return p;
}

const NearScene& nearScene() {
  static const NearScene scene = [] {
    NearScene s;
    synth::SynthConfig cfg;
    cfg.camera = Camera::kannalaBrandt4(256, 256, 150, 150, 127.5, 127.5, -0.0066, 0.0473, -0.0458, 0.009);
    cfg.baseline = 0.35;
    cfg.nearest = 0.5;
    cfg.seed = 6;
    cfg.samplesPerAxis = CS_SANITIZED ? 1 : 2;
    s.pair = synth::renderPair(cfg);
    const synth::SynthPair& p = s.pair;
    s.truth = groundTruthWarp(p.rig, p.depthLeft);
    s.nonOccluded = nonOccludedMask(p.rig, p.depthLeft, &p.depthRight);
    s.nearObject = ImageU8(256, 256, 0);
    const BuiltCamera cam0(p.rig.cam0);
    for (int y = 0; y < 256; ++y)
      for (int x = 0; x < 256; ++x) {
        Vec3<double> r;
        if (!s.nonOccluded(x, y) || !std::isfinite(s.truth(x, y).x) || !cam0.unproject(Vec2<double>(x, y), r)) continue;
        synth::Hit hit;
        const synth::Ray ray{p.pose0.centre, p.pose0.rotation * Eigen::Vector3d(r.x(), r.y(), r.z())};
        s.nearObject(x, y) = p.scene.intersect(ray, hit) && p.scene.shapes()[hit.shape].name == "near0";
      }
    s.plain = Stereo(p.rig, nearPreset("variational"), "cpu").compute(p.left, p.right);
    s.initialised = Stereo(p.rig, nearPreset("quality"), "cpu").compute(p.left, p.right);
    if (!CS_SANITIZED) s.banded = Stereo(p.rig, nearPreset("realtime"), "cpu").compute(p.left, p.right);
    return s;
  }();
  return scene;
}

}  // namespace

TEST_CASE("a near object ~100 px away is recovered with the initialiser (preset quality) and lost without it") {
  const NearScene& s = nearScene();
  if (!test::accuracyMeasured()) return;
  const Accuracy plain = accuracyOn(s, s.plain, s.nearObject), init = accuracyOn(s, s.initialised, s.nearObject);
  const Metrics all0 = evaluate(s.pair.rig, s.plain.warp, s.plain.depth.radial, s.pair.depthLeft, &s.pair.depthRight);
  const Metrics all1 =
      evaluate(s.pair.rig, s.initialised.warp, s.initialised.depth.radial, s.pair.depthLeft, &s.pair.depthRight);
  MESSAGE("near object: " << init.pixels << " px, true |w| median " << init.medianTruth << " px");
  MESSAGE("default: near tau>1 " << plain.tau1 << " %, EPE " << plain.epe << " px; all tau>3 " << all0.tau3 << " % ("
                                 << s.plain.totalMs << " ms)");
  MESSAGE("quality: near tau>1 " << init.tau1 << " %, EPE " << init.epe << " px; all tau>3 " << all1.tau3 << " % ("
                                 << s.initialised.totalMs << " ms)");
  // The scene is what this test claims.
  REQUIRE(init.pixels > 2000);
  CHECK(init.medianTruth > 90);
  CHECK(init.medianTruth < 120);
  // Without the initialiser the object is lost: every pixel off by more than a pixel.
  CHECK(plain.tau1 > 95);
  CHECK(plain.epe > 60);
  // With it, measured (2026-11): tau>1 51 %, EPE 20 px on the object (default: 100 %, 97
  // px), and tau>3 over the image 23.5 % vs 29.7 %. The bounds leave room for renderer
  // and solver changes, not for an initialiser that does not reach the object.
  CHECK(init.tau1 < 65);
  CHECK(init.epe < 30);
  CHECK(all1.tau3 < all0.tau3 - 3);
}

TEST_CASE("the band sweep (preset realtime) reaches the near object ~100 px away too") {
  const NearScene& s = nearScene();
  REQUIRE(preset("realtime").initBand > 0);
  if (!test::accuracyMeasured()) return;
  const Accuracy banded = accuracyOn(s, s.banded, s.nearObject);
  MESSAGE("realtime: near tau>1 " << banded.tau1 << " %, EPE " << banded.epe << " px (" << s.banded.totalMs << " ms)");
  CHECK(banded.tau1 < 65);
  CHECK(banded.epe < 30);
}

TEST_CASE("confidence: in [0, 1] where valid, NaN where not, also without the initialiser, low in occlusions") {
  const NearScene& s = nearScene();
  CHECK(s.plain.confidence.width == s.plain.valid.width);
  const DepthResult& r = s.initialised;
  REQUIRE(r.confidence.width == r.valid.width);
  REQUIRE(r.confidence.height == r.valid.height);
  long long bad = 0, valid = 0, occludedCount = 0, visibleCount = 0;
  double occluded = 0, visible = 0;
  for (size_t i = 0; i < r.valid.size(); ++i) {
    const float c = r.confidence.data[i];
    if (!r.valid.data[i]) {
      bad += !std::isnan(c);
      continue;
    }
    ++valid;
    bad += !(c >= 0.f && c <= 1.f);
    // Occluded: a surface of image 0 that image 1 does not see (ground truth).
    if (!std::isfinite(s.truth.data[i].x)) continue;
    (s.nonOccluded.data[i] ? visible : occluded) += c;
    ++(s.nonOccluded.data[i] ? visibleCount : occludedCount);
  }
  occluded /= std::max(1LL, occludedCount);
  visible /= std::max(1LL, visibleCount);
  MESSAGE("mean confidence: " << visible << " on " << visibleCount << " visible pixels, " << occluded << " on "
                              << occludedCount << " occluded ones");
  CHECK(valid > 30000);
  CHECK(bad == 0);
  REQUIRE(occludedCount > 1000);
  // Measured 0.18 occluded (or outside image 1) vs 0.85 visible.
  CHECK(occluded < visible - 0.4);
}

TEST_CASE("warp schedule: the taper from the coarsest level, the sweep's levels apart") {
  Params p = preset("variational");
  CHECK(warpSchedule(p, 5) == std::vector<int>{30, 30, 30, 30, 30});
  p.warpsTaper = 10;
  CHECK(warpSchedule(p, 5) == std::vector<int>{1, 1, 10, 20, 30});  // never fewer than one
  CHECK(warpSchedule(p, 2) == std::vector<int>{20, 30});            // counted from the coarsest there is
  p.initWarps = 2;
  CHECK(warpSchedule(p, 5) == std::vector<int>{1, 1, 10, 20, 30});  // initWarps needs the initialiser
  p.init = Params::Init::PlaneSweep;
  p.initLevel = 1;
  CHECK(warpSchedule(p, 5) == std::vector<int>{2, 2, 10, 20, 30});
  CHECK(warpSchedule(preset("quality"), 5) == std::vector<int>{30, 30, 30, 30, 30});
  // A band sweep's full sweep initialises the level above: initWarps from there down.
  p.initBand = 32;
  CHECK(sweepBanded(p, 5));
  CHECK(warpSchedule(p, 5) == std::vector<int>{2, 2, 2, 20, 30});
  CHECK(warpSchedule(preset("realtime"), 5) == std::vector<int>{2, 2, 2, 20, 30});
  // A warm frame: the levels above the carried one (2) briefly, one warp at full resolution.
  CHECK(warpSchedule(preset("realtime"), 5, true) == std::vector<int>{1, 2, 2, 3, 3});
  Params skipped = preset("realtime");
  skipped.warmCoarseWarps = 0;
  skipped.warmFullResWarps = 0;
  CHECK(warpSchedule(skipped, 5, true) == std::vector<int>{2, 2, 2, 0, 0});
  CHECK(!sweepBanded(p, 2));                            // no level above the sweep's: a full sweep
  CHECK(warpSchedule(p, 2) == std::vector<int>{2, 2});  // the sweep at the coarsest, both refine
  p.initBand = 0;
  p.initLevel = 7;  // clamped to the coarsest level, as the sweep is
  CHECK(sweepLevel(p, 3) == 2);
  CHECK(warpSchedule(p, 3) == std::vector<int>{2, 2, 2});
}

TEST_CASE("init parameters: validation, parseInit / initName, preset quality") {
  const Params good = preset("quality");
  CHECK(good.init == Params::Init::PlaneSweep);
  CHECK(preset("variational").init == Params::Init::None);
  CHECK(preset("realtime").init == Params::Init::PlaneSweep);
  CHECK(preset("realtime").initLevel == 1);
  CHECK(preset("fast").init == Params::Init::PlaneSweep);
  CHECK(preset("fast").initLevel == 2);
  CHECK(preset("paper").init == Params::Init::None);
  CHECK(preset("paper").dataTerm == Params::DataTerm::Brightness);
  const auto names = presetNames();
  CHECK(std::find(names.begin(), names.end(), "quality") != names.end());
  // quality is variational plus the initialiser and the edge-aware upsampling.
  CHECK(good.edgeUpsample);
  CHECK(preset("realtime").edgeUpsample);
  CHECK(preset("fast").edgeUpsample);
  CHECK(!preset("variational").edgeUpsample);
  CHECK(!preset("paper").edgeUpsample);
  Params same = good;
  same.init = Params::Init::None;
  same.edgeUpsample = false;
  CHECK(describe(same) == describe(preset("variational")));
  CHECK(describe(good).find("init=planesweep") != std::string::npos);
  good.validate();

  CHECK(parseInit("planesweep") == Params::Init::PlaneSweep);
  CHECK(parseInit("none") == Params::Init::None);
  for (const char* n : {"none", "planesweep"}) CHECK(initName(parseInit(n)) == n);
  CHECK_THROWS_WITH_AS(parseInit("foo"), doctest::Contains("unknown initialisation 'foo'"), Error);
  CHECK_THROWS_WITH_AS(parseInit("foo"), doctest::Contains("none, planesweep"), Error);
  CHECK_THROWS_AS(parseInit("PlaneSweep"), Error);

  auto refused = [&](const char* field, auto set) {
    Params p = good;
    set(p);
    CHECK_THROWS_WITH_AS(p.validate(), doctest::Contains(field), Error);
  };
  refused("initLevel", [](Params& p) { p.initLevel = -1; });
  refused("initLevel", [](Params& p) { p.initLevel = 12; });
  refused("initMaxParallaxDeg", [](Params& p) { p.initMaxParallaxDeg = 0; });
  refused("initMaxParallaxDeg", [](Params& p) { p.initMaxParallaxDeg = 90; });
  refused("initMaxParallaxDeg", [](Params& p) { p.initMaxParallaxDeg = NAN; });
  refused("initPxPerPlane", [](Params& p) { p.initPxPerPlane = 0.2; });
  refused("initPxPerPlane", [](Params& p) { p.initPxPerPlane = 17; });
  refused("initRadius", [](Params& p) { p.initRadius = 0; });
  refused("initRadius", [](Params& p) { p.initRadius = 8; });
  refused("lrTolerancePx", [](Params& p) { p.lrTolerancePx = 0; });
  refused("lrTolerancePx", [](Params& p) { p.lrTolerancePx = INFINITY; });
  refused("initAccept", [](Params& p) { p.initAccept = -0.1f; });
  refused("initAccept", [](Params& p) { p.initAccept = 1.5f; });
  refused("occlusionWeight", [](Params& p) { p.occlusionWeight = -0.1f; });
  refused("occlusionWeight", [](Params& p) { p.occlusionWeight = 1.5f; });
  refused("occlusionWeight", [](Params& p) { p.occlusionWeight = NAN; });
  refused("initP1", [](Params& p) { p.initP1 = -0.01f; });
  refused("initP1", [](Params& p) { p.initP1 = 0.6f, p.initP2 = 0.5f; });
  refused("initP2", [](Params& p) { p.initP2 = NAN; });
  // The ends of each range are accepted.
  Params edge = good;
  edge.initLevel = 0, edge.initRadius = 7, edge.initPxPerPlane = 16, edge.occlusionWeight = 0, edge.initAccept = 1;
  edge.initP1 = edge.initP2 = 0.f;  // no smoothness: winner-take-all on the window costs
  edge.validate();
  edge.initLevel = 11, edge.initRadius = 1, edge.initPxPerPlane = 0.25, edge.occlusionWeight = 1, edge.initAccept = 0;
  edge.validate();
}

TEST_CASE("setPose with another baseline length and the initialiser on: same warp, depth scaled") {
  synth::SynthConfig cfg;
  cfg.camera = synth::defaultFisheye(128);
  cfg.baseline = 0.2;
  cfg.nearest = 1.0;
  cfg.seed = 3;
  // Under the sanitizers one sample per pixel and short solves (test_util.hpp): the warp
  // and the solve are the same for either baseline whatever the image and the number of warps.
  cfg.samplesPerAxis = CS_SANITIZED ? 1 : 2;
  const synth::SynthPair pair = synth::renderPair(cfg);
  Params quality = preset("quality");
  quality.warps = test::shortUnderSanitizers(quality.warps);
  Stereo stereo(pair.rig, quality, "cpu");
  const DepthResult before = stereo.compute(pair.left, pair.right);
  // Twice the baseline, same direction: the hypotheses move with it (qMax halves), so the
  // images' correspondences, and with them the whole solve, are unchanged and every
  // depth doubles.
  stereo.setPose(pair.rig.R, 2.0 * pair.rig.t);
  const DepthResult twice = stereo.compute(pair.left, pair.right);
  stereo.setPose(pair.rig.R, pair.rig.t);
  const DepthResult again = stereo.compute(pair.left, pair.right);
  REQUIRE(twice.valid.data == before.valid.data);
  CHECK(again.valid.data == before.valid.data);
  long long valid = 0, sameWarp = 0, doubled = 0, finiteDepth = 0, repeated = 0;
  for (size_t i = 0; i < before.valid.size(); ++i) {
    if (!before.valid.data[i]) continue;
    ++valid;
    const Vec2f a = before.warp.data[i], b = twice.warp.data[i];
    sameWarp += std::hypot(a.x - b.x, a.y - b.y) <= 1e-3f;
    repeated += again.disparity.data[i] == before.disparity.data[i];
    const float d0 = before.depth.radial.data[i], d1 = twice.depth.radial.data[i];
    if (!std::isfinite(d0) || !std::isfinite(d1)) continue;
    ++finiteDepth;
    doubled += std::abs(d1 - 2.f * d0) <= 1e-3f * d1;
  }
  MESSAGE(valid << " valid: " << sameWarp << " same warp, " << doubled << " of " << finiteDepth
                << " finite depths doubled, " << repeated << " repeated exactly after the pose came back");
  CHECK(valid > 5000);
  CHECK(!twice.confidence.empty());
  CHECK(sameWarp >= 0.99 * valid);
  CHECK(doubled >= 0.99 * finiteDepth);
  CHECK(repeated == valid);
}

TEST_CASE("progress rises to 1 with the plane sweep counted as its share of the work") {
  synth::SynthConfig cfg;
  cfg.camera = synth::defaultFisheye(96);
  cfg.baseline = 0.2;
  const synth::SynthPair pair = synth::renderPair(cfg);
  for (const bool initialiser : {false, true}) {
    CAPTURE(initialiser);
    Params params = preset(initialiser ? "quality" : "variational");
    params.warps = 3;
    Stereo stereo(pair.rig, params, "cpu");
    std::vector<double> reports;
    stereo.setProgress([&](double f) { reports.push_back(f); });
    stereo.compute(pair.left, pair.right);
    const size_t warps = pyramidPlan(pair.left.width, pair.left.height, params).size() * params.warps;
    REQUIRE(reports.size() == warps + (initialiser ? 1 : 0));
    std::vector<double> steps{reports.front()};
    for (size_t i = 1; i < reports.size(); ++i) {
      CHECK(reports[i] >= reports[i - 1]);
      steps.push_back(reports[i] - reports[i - 1]);
    }
    CHECK(reports.back() == doctest::Approx(1.0).epsilon(1e-12));
    // The sweep (a quarter of a warp per hypothesis, dozens of hypotheses) is reported as
    // one step that outweighs any warp's by far.
    std::sort(steps.begin(), steps.end());
    if (initialiser) CHECK(steps.back() > 4.0 * steps[steps.size() - 2]);
  }
}
