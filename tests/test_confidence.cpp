// The result's confidence, the left-right round trip (lr_check) and points at infinity
// (issue 28; docs/confidence.md), end to end on the CPU oracle: a small urban pair with sky.
#include <cmath>

#include "curvestereo/metrics.hpp"
#include "curvestereo/stereo.hpp"
#include "test_util.hpp"

using namespace cs;

namespace {

struct Solved {
  synth::SynthPair pair;
  DepthResult plain, checked;  // realtime, and realtime with lr_check
};

const Solved& solved() {
  static const Solved s = [] {
    Solved r;
    r.pair = test::smallSynthPair(160, "binocular", 0.12, 5);
    Params p = preset("realtime");
    r.plain = Stereo(r.pair.rig, p, "cpu").compute(r.pair.left, r.pair.right);
    p.lrCheck = true;
    r.checked = Stereo(r.pair.rig, p, "cpu").compute(r.pair.left, r.pair.right);
    return r;
  }();
  return s;
}

bool allNaN(const DepthResult& r, size_t i) {
  return std::isnan(r.depth.radial.data[i]) && std::isnan(r.disparity.data[i]) && std::isnan(r.warp.data[i].x) &&
         std::isnan(r.depth.points.data[i].x) && std::isnan(r.confidence.data[i]);
}

}  // namespace

TEST_CASE("confidence: in [0, 1] where valid, NaN where not, and it ranks the errors") {
  const Solved& s = solved();
  const DepthResult& r = s.plain;
  REQUIRE(r.confidence.width == r.valid.width);
  long long bad = 0;
  for (size_t i = 0; i < r.valid.size(); ++i)
    bad += r.valid.data[i] ? !(r.confidence.data[i] >= 0.f && r.confidence.data[i] <= 1.f) : !allNaN(r, i);
  CHECK(bad == 0);
  ImageF error;
  evaluate(s.pair.rig, r.warp, r.depth.radial, s.pair.depthLeft, &s.pair.depthRight, &error);
  const Sparsification curve = sparsification(error, r.confidence, 1.0);
  REQUIRE(curve.keptPercent.size() == 11);
  MESSAGE("tau>1 all " << curve.tau[0] << " %, most confident 80 % " << curve.tau[4] << " % (oracle "
                       << curve.oracleTau[4] << " %), area " << curve.area << " (oracle " << curve.oracleArea << ")");
  CHECK(curve.oracleArea <= curve.area);
  // A confidence that did not rank would keep tau flat as pixels are dropped.
  CHECK(curve.tau[4] < 0.75 * curve.tau[0]);
  CHECK(curve.tau.back() < 0.6 * curve.tau[0]);
}

TEST_CASE("sparsification: the oracle's curve falls as fast as the errors allow") {
  ImageF error(10, 1), confidence(10, 1);
  for (int i = 0; i < 10; ++i) {
    error.data[size_t(i)] = i < 3 ? 5.f : 0.1f;    // three bad pixels
    confidence.data[size_t(i)] = float(i) / 10.f;  // ranked worst first: the bad ones are the least confident
  }
  error.data[9] = INFINITY;  // no estimate: ranked last whatever its confidence
  const Sparsification s = sparsification(error, confidence, 1.0);
  CHECK(s.tau[0] == doctest::Approx(40.0));
  CHECK(s.oracleTau[0] == doctest::Approx(40.0));
  CHECK(s.tau.back() == doctest::Approx(0.0));  // the 5 most confident are all good
  CHECK(s.oracleTau.back() == doctest::Approx(0.0));
  CHECK_THROWS_AS(sparsification(error, ImageF(3, 3), 1.0), Error);
}

TEST_CASE("lr_check: only round trips that pass stay valid, the rest are NaN everywhere") {
  const Solved& s = solved();
  const DepthResult &a = s.plain, &b = s.checked;
  long long validA = 0, validB = 0, gained = 0, notNaN = 0;
  for (size_t i = 0; i < a.valid.size(); ++i) {
    validA += a.valid.data[i];
    validB += b.valid.data[i];
    gained += b.valid.data[i] && !a.valid.data[i];
    if (!b.valid.data[i]) notNaN += !allNaN(b, i);
  }
  const long long fieldOfView = validA;  // realtime without the check leaves every pixel of it valid
  MESSAGE("lr_check keeps " << validB << " of " << validA << " pixels; pass share " << b.lrPassShare);
  CHECK(gained == 0);
  CHECK(notNaN == 0);
  CHECK(validB < validA);
  CHECK(b.lrPassShare > 0.7);
  CHECK(b.lrPassShare == doctest::Approx(double(validB) / double(fieldOfView)).epsilon(0.02));
  CHECK(std::isnan(a.lrPassShare));
  // The pixels it removes are the worse ones.
  const Metrics ma = evaluate(s.pair.rig, a.warp, a.depth.radial, s.pair.depthLeft, nullptr);
  ImageF errorB;
  evaluate(s.pair.rig, b.warp, b.depth.radial, s.pair.depthLeft, nullptr, &errorB);
  long long kept = 0, keptBad = 0;
  for (float e : errorB.data)
    if (std::isfinite(e)) ++kept, keptBad += e > 1.f;
  CHECK(100.0 * double(keptBad) / double(kept) < ma.tau1);
}

TEST_CASE("infinity: a disparity below infinity_px is +inf, a pixel the image cannot fix is invalid") {
  const Solved& s = solved();
  const DepthResult& r = s.plain;
  const float limit = preset("realtime").infinityPx;
  long long small = 0, wrong = 0;
  for (size_t i = 0; i < r.valid.size(); ++i) {
    if (!r.valid.data[i]) continue;
    const Vec2f w = r.warp.data[i];
    if (w.x * w.x + w.y * w.y >= limit * limit) continue;
    ++small;
    wrong +=
        !(std::isinf(r.depth.radial.data[i]) && r.depth.radial.data[i] > 0) || !std::isnan(r.depth.points.data[i].x);
  }
  const Metrics m = evaluate(s.pair.rig, r.warp, r.depth.radial, s.pair.depthLeft, nullptr);
  MESSAGE(small << " px below " << limit << " px of disparity; sky " << m.skyPixels << " px, " << m.sky
                << " % at +inf or invalid");
  CHECK(small > 100);  // the scene's sky and far background
  CHECK(wrong == 0);
  // max_deviation_px: plain pixels (here the sky's smooth parts) become invalid, never
  // pixels of the densely textured surfaces.
  Params p = preset("realtime");
  p.maxDeviationPx = 2.f;
  const DepthResult strict = Stereo(s.pair.rig, p, "cpu").compute(s.pair.left, s.pair.right);
  const Metrics ms = evaluate(s.pair.rig, strict.warp, strict.depth.radial, s.pair.depthLeft, nullptr);
  CHECK(ms.sky >= m.sky);
  CHECK(ms.density > m.density - 1.0);
}

TEST_CASE("infinity_bound_px: a disparity the image bounds below it is +inf; nothing else changes") {
  const Solved& s = solved();
  const DepthResult& on = s.plain;
  const float bound = preset("realtime").infinityBoundPx;
  REQUIRE(bound > 0.f);
  Params p = preset("realtime");
  p.infinityBoundPx = 0.f;
  const DepthResult off = Stereo(s.pair.rig, p, "cpu").compute(s.pair.left, s.pair.right);
  long long became = 0, beyond = 0, changed = 0;
  for (size_t i = 0; i < on.valid.size(); ++i) {
    const Vec2f w = on.warp.data[i];
    changed += !(w.x == off.warp.data[i].x && w.y == off.warp.data[i].y) && std::isfinite(w.x);
    const bool infOn = std::isinf(on.depth.radial.data[i]), infOff = std::isinf(off.depth.radial.data[i]);
    if (infOn == infOff) continue;
    ++became;
    beyond += !infOn || w.x * w.x + w.y * w.y > bound * bound;
  }
  const Metrics mOn = evaluate(s.pair.rig, on.warp, on.depth.radial, s.pair.depthLeft, nullptr);
  const Metrics mOff = evaluate(s.pair.rig, off.warp, off.depth.radial, s.pair.depthLeft, nullptr);
  MESSAGE(became << " px more at +inf; sky " << mOff.sky << " -> " << mOn.sky << " %");
  CHECK(changed == 0);
  CHECK(became > 0);
  CHECK(beyond == 0);  // only ever finite -> +inf, and only below the bound
  CHECK(mOn.sky > mOff.sky);
  CHECK(mOn.tau1 == mOff.tau1);
}

TEST_CASE("reject_below: pixels below the confidence are invalid") {
  const Solved& s = solved();
  Params p = preset("realtime");
  p.rejectBelow = 0.5f;
  const DepthResult r = Stereo(s.pair.rig, p, "cpu").compute(s.pair.left, s.pair.right);
  long long low = 0, valid = 0;
  for (size_t i = 0; i < r.valid.size(); ++i)
    if (r.valid.data[i]) ++valid, low += r.confidence.data[i] < 0.5f;
  CHECK(valid > 0);
  CHECK(low == 0);
}
