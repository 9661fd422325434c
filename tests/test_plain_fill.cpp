// Plain regions (core/src/plain_fill.cpp, Params::plainFill): the host's plane fit from a
// plain region's confident border, on supports made from a known floor.
#include <algorithm>
#include <cmath>
#include <vector>

#include <doctest/doctest.h>
#include "curvestereo/camera.hpp"
#include "curvestereo/triangulate.hpp"
#include "plain_fill.hpp"

using namespace cs;

namespace {

constexpr int kFull = 160, kLevel = 40;  // full resolution and the fill level (a quarter)

Camera fisheye() { return Camera::kannalaBrandt4(kFull, kFull, 52, 52, 79.5, 79.5, 0.01, -0.005, 0.002, -0.0005); }

const Eigen::Vector3d kTPrime(-0.1, 0.002, 0.001);
const Eigen::Vector3d kFloor(0.0, 1.0 / 1.2, 0.0);  // q = a . ray: a floor 1.2 m below camera 0

// Support under each level pixel (Backend::plainSupport's layout): rays steeper than 20
// degrees below the horizon see the plain floor; the rest is textured and carries the warp
// `q(ray)` gives, from the level pixel's full-resolution centre with the given confidence.
template <class InverseDepth>
std::vector<float> supports(InverseDepth q, float confidence) {
  const BuiltCamera cam(fisheye());
  std::vector<float> s(size_t(kLevel) * kLevel * kPlainSupportChannels, 0.f);
  for (int y = 0; y < kLevel; ++y)
    for (int x = 0; x < kLevel; ++x) {
      float* o = &s[kPlainSupportChannels * (size_t(y) * kLevel + x)];
      const Vec2<double> X(4 * x + 1, 4 * y + 1);
      Vec3<double> ray;
      o[4] = -1.f, o[5] = -1.f;
      if (!cam.unproject(X, ray) || ray.z() < 0.05) continue;
      o[5] = ray.y() > 0.34 ? 1e-6f : 1.f;  // plain floor, or texture
      const double inverse = q(ray, x, y);
      Vec2<double> w;
      if (o[5] < 0.5f || !warpFromDepth(cam, kTPrime, X, inverse > 0 ? 1.0 / inverse : INFINITY, w)) continue;
      o[0] = float(X.x()), o[1] = float(X.y()), o[2] = float(w.x()), o[3] = float(w.y()), o[4] = confidence;
    }
  return s;
}

PlainPlanes find(const std::vector<float>& support) {
  PlainFillParams p;
  p.noise = 0.01f;
  p.qMax = 10.0;
  return findPlainPlanes(plainRays(fisheye(), kTPrime, kLevel, kLevel), fisheye(), kTPrime, kLevel, kLevel, support, p);
}

}  // namespace

TEST_CASE("the plane most of a plain floor's border agrees on fills it, a near occluder outvoted") {
  // A quarter of the border (every fourth column) is a near object in front of the floor.
  const PlainPlanes found = find(supports(
      [](const Vec3<double>& ray, int x, int) { return x % 4 == 0 ? 2.0 * kFloor.dot(ray) + 0.5 : kFloor.dot(ray); },
      0.9f));
  REQUIRE(found.planes.size() == 1);
  CHECK((found.planes[0].cast<double>() - kFloor).cwiseAbs().maxCoeff() < 1e-3);
  long long plain = 0, filled = 0;
  const std::vector<float> s = supports([](const Vec3<double>& ray, int, int) { return kFloor.dot(ray); }, 0.9f);
  std::vector<float> confidences;
  for (size_t i = 0; i < found.labels.size() / 2; ++i) {
    plain += s[kPlainSupportChannels * i + 5] == 1e-6f;
    filled += found.labels[2 * i] == 0.f;
    if (found.labels[2 * i] == 0.f) confidences.push_back(found.labels[2 * i + 1]);
  }
  // Filled where the plane's deviation is at most 1 px: confidence 1 / (1 + (1 / 0.5)^2) or more.
  REQUIRE(!confidences.empty());
  std::sort(confidences.begin(), confidences.end());
  CHECK(confidences.front() >= 0.2f);
  CHECK(confidences.front() < 0.5f);  // far from the border the plane is less certain
  CHECK(confidences[confidences.size() / 2] > 0.5f);
  MESSAGE("plain " << plain << ", filled " << filled);
  CHECK(plain > 100);
  // The border is above the floor only (below it is the rim): the plane is extrapolated
  // towards the rim, where its deviation passes 1 px and a few rows stay unfilled.
  CHECK(filled >= 0.75 * double(plain));
  CHECK(filled < plain);
  CHECK(found.pixels == filled);
}

TEST_CASE("no plane where the border disagrees with itself or is not confident") {
  // Inverse depths scattered over [0.05, 3.05] (0.3 to 20 m; about 15 px of motion here): no
  // plane holds 40 % of them within the 1 px bound.
  const PlainPlanes scattered = find(supports(
      [](const Vec3<double>&, int x, int y) { return 0.05 + 3.0 * std::fmod(0.618034 * (x * 41 + y * 17), 1.0); },
      0.9f));
  CHECK(scattered.regions >= 1);
  CHECK(scattered.planes.empty());
  // The floor's border, but no pixel confident enough to vote.
  const PlainPlanes unsure = find(supports([](const Vec3<double>& ray, int, int) { return kFloor.dot(ray); }, 0.3f));
  CHECK(unsure.planes.empty());
  for (size_t i = 0; i < unsure.labels.size(); i += 2) CHECK(unsure.labels[i] == -1.f);
}
