// The golden cases of a sequence's kernels (carryEstimate, temporalFilter) and of the
// result's confidence (roundTrip, resultConfidence); the rest are in golden_cases.cpp.
#include <Eigen/Geometry>
#include <cmath>
#include <limits>

#include "golden_inputs.hpp"

namespace cs::golden {

// --- sequences ---

// A state of a scene: a tilted plane 2-4 m away, a near box (q 1.5) over part of it, a
// patch at infinity (q 0) and holes (q -1); variances in px^2.
Host sequenceState(int w, int h) {
  Host st(w, h, 2);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float q = 0.25f + 0.25f * float(x) / float(w) + 0.05f * float(y) / float(h);
      if (x >= 14 && x < 24 && y >= 10 && y < 22) q = 1.5f;
      if (x >= 30 && y < 8) q = 0.f;
      if ((x * 7 + y * 3) % 29 == 0) q = -1.f;
      st.at(x, y, 0) = q;
      st.at(x, y, 1) = 0.1f + 0.5f * hashNoise(uint32_t(y * w + x) * 613u + 7u);
    }
  return st;
}

// Camera 0 turns 6 degrees about y and 3 about x and moves 12 cm, mostly forward.
Host sequenceMotion() {
  const Eigen::Matrix3d R =
      (Eigen::AngleAxisd(0.105, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(0.052, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  Host m(kMotionFloats, 1, 1);
  for (int i = 0; i < 9; ++i) m.v[size_t(i)] = float(R(i / 3, i % 3));
  m.v[9] = 0.04f, m.v[10] = -0.02f, m.v[11] = 0.11f;
  return m;
}

// Into the same grid from this frame's depth (the temporal filter's prior): one step from the
// guess, which holds NaN, +inf and non-positive values too.
std::vector<Output> carryEstimateCase(Backend& b) {
  Session s{b};
  Host state = sequenceState(kW, kH), motion = sequenceMotion(), mask = discMask(kW, kH);
  Host guess = noise(kW, kH, 1, 61, 0.5f);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      float& g = guess.at(x, y);
      g = 2.5f + g;
      if (x >= 15 && x < 25 && y >= 12 && y < 22) g = 0.7f;
      if ((x + 2 * y) % 17 == 0) g = std::numeric_limits<float>::quiet_NaN();
      if ((x + 2 * y) % 19 == 0) g = std::numeric_limits<float>::infinity();
      if ((3 * x + y) % 23 == 0) g = (x % 2) ? 0.f : -1.f;
    }
  const CameraParams cam = fieldsParams().cam0;
  Buffer dst = s.make(kW, kH, 2);
  b.carryEstimate(dst, s.put(state), s.put(guess), s.put(motion), s.put(mask), {cam, cam, {0, 0, 0}, 1});
  // Double geometry on every backend, one nearest-pixel lookup per step (a lookup would only
  // change at a rounding tie), q in double rounded to float once.
  return within({s.get("carry_prior", dst)}, {1e-5, 1e-12});
}

// Into a coarser grid of camera 1' (extraT = t'), by three fixed-point steps from the state
// itself: the warm start's proposals.
std::vector<Output> carryEstimateCoarseCase(Backend& b) {
  Session s{b};
  Host state = sequenceState(kW, kH), motion = sequenceMotion();
  const int cw = (kW + 1) / 2, ch = (kH + 1) / 2;
  Host mask = discMask(cw, ch);
  Camera coarse = toCamera(fieldsParams().cam0).scaled(0.5);
  coarse.width = cw, coarse.height = ch;
  CarryParams p{fieldsParams().cam0, toCameraParams(coarse), {-0.064, 0.001, 0.002}, 3};
  Buffer dst = s.make(cw, ch, 2);
  b.carryEstimate(dst, s.put(state), Buffer{}, s.put(motion), s.put(mask), p);
  return within({s.get("carry_coarse", dst)}, {1e-5, 1e-12});  // as carry_prior
}

// A prior that agrees in places (filtered), disagrees in others (reset: the gate), is missing
// in some; a measurement at infinity, NaN and a confidence that falls across the image.
std::vector<Output> temporalFilterCase(Backend& b) {
  Session s{b};
  Host prior = sequenceState(kW, kH), mask = discMask(kW, kH), radial(kW, kH, 1), confidence(kW, kH, 1);
  Host u = noise(kW, kH, 1, 71, 3.f), w = noise(kW, kH, 2, 72, 3.f);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const float q = prior.at(x, y, 0);
      // Within a fraction of a px of the prior, or far off on the box (a moving object).
      const float qm = std::max(0.f, q) + 0.004f * (2.f * hashNoise(uint32_t(y * kW + x) * 977u + 5u) - 1.f);
      radial.at(x, y) = (x >= 14 && x < 24 && y >= 10 && y < 16) ? 1.f / 0.6f : 1.f / std::max(qm, 1e-3f);
      if (x >= 30 && y < 6) radial.at(x, y) = std::numeric_limits<float>::infinity();
      if ((x + 3 * y) % 31 == 0) radial.at(x, y) = std::numeric_limits<float>::quiet_NaN();
      confidence.at(x, y) = float(x) / float(kW - 1);
    }
  const FieldsParams fp = fieldsParams();
  TemporalParams p{fp.cam0, {-0.064, 0.001, 0.002}, 0.8f, 3.f, 0.5f, 0.1f, 0.1f};
  Buffer state = s.make(kW, kH, 2), ub = s.put(u), wb = s.put(w), rb = s.put(radial), points = s.make(kW, kH, 3);
  b.temporalFilter(state, ub, wb, s.put(prior), rb, points, s.put(confidence), s.put(mask), p);
  // The depths are triangulated again in the camera models' precision, reaching 1000 m
  // (1 / 1e-3): metres as triangulate's (float models on Vulkan: 5e-4 m at most).
  std::vector<Output> out = {s.get("temporal_state", state), s.get("temporal_u", ub), s.get("temporal_w", wb)};
  for (Output& o : within({s.get("temporal_radial", rb), s.get("temporal_points", points)}, {1e-2, 1e-8}))
    out.push_back(std::move(o));
  return out;
}

// --- plain regions ---

// Confidences with ties, NaN and a block with nothing masked, under a coarse grid a quarter
// of the size (rounded up: the last blocks are narrower) and under one of an uneven ratio.
std::vector<Output> plainSupportCase(Backend& b) {
  Session s{b};
  Host confidence = noise(kW, kH, 1, 91, 0.5f), w = noise(kW, kH, 2, 92, 3.f), mask = discMask(kW, kH);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      float& c = confidence.at(x, y);
      c = 0.5f + c;
      if ((x + 3 * y) % 13 == 0) c = std::numeric_limits<float>::quiet_NaN();
      if (x >= 8 && x < 12 && y >= 8 && y < 12) c = 0.75f;  // a block of equals: the first wins
    }
  Buffer cb = s.put(confidence), wb = s.put(w), mb = s.put(mask);
  const int qw = (kW + 3) / 4, qh = (kH + 3) / 4;
  Host quarterImage = texture(qw, qh, 95), quarterMask = discMask(qw, qh);
  Host unevenImage = texture(13, 11, 96), unevenMask = discMask(13, 11);
  for (int x = 0; x < 6; ++x) quarterImage.at(x, 5) = 0.5f;  // a plain row: variance near 0
  Buffer quarter = s.make(qw, qh, 6), uneven = s.make(13, 11, 6);
  b.plainSupport(quarter, cb, wb, mb, s.put(quarterImage), s.put(quarterMask));
  b.plainSupport(uneven, cb, wb, mb, s.put(unevenImage), s.put(unevenMask));
  // Comparisons and copies but for the variance (channel 5, values about 1e-3): float sums
  // in the oracle's order; Vulkan's division may round to 2.5 ulp.
  return within({s.get("plain_support", quarter), s.get("plain_support_uneven", uneven)}, {1e-9, 1e-12});
}

// Three planes over a coarse grid of labels (-1 and NaN: none; 5: beyond the planes given),
// each with a confidence: a floor, a wall, and a plane behind some rays (q < 0: those keep
// their values).
std::vector<Output> fillPlanesCase(Backend& b) {
  Session s{b};
  const int lw = (kW + 3) / 4, lh = (kH + 3) / 4;
  Host u = noise(kW, kH, 1, 93, 2.f), w = noise(kW, kH, 2, 94, 2.f), mask = discMask(kW, kH), labels(lw, lh, 2);
  for (int y = 0; y < lh; ++y)
    for (int x = 0; x < lw; ++x) {
      labels.at(x, y, 0) = float((x + 2 * y) % 5) - 1.f;  // -1, 0, 1, 2, 3
      labels.at(x, y, 1) = 0.3f + 0.05f * float(x);
    }
  labels.at(1, 1) = 5.f;
  labels.at(2, 1) = std::numeric_limits<float>::quiet_NaN();
  Host planes(9, 1, 1);
  const float a[9] = {0.f, 0.6f, 0.05f, 0.02f, -0.01f, 0.4f, -0.9f, 0.1f, 0.2f};
  std::copy(a, a + 9, planes.v.begin());
  Buffer ub = s.put(u), wb = s.put(w), cb = s.make(kW, kH, 1);
  b.fill(cb, 7.f);  // every pixel written
  const FieldsParams f = fieldsParams();
  b.fillPlanes(ub, wb, cb, s.put(labels), s.put(planes), s.put(mask), f.cam0, f.t);
  // Double geometry on every backend, rounded to float once (as carryEstimate).
  return within({s.get("fill_planes_u", ub), s.get("fill_planes_w", wb), s.get("fill_planes_confidence", cb)},
                {1e-5, 1e-12});
}

// --- the result's confidence ---

// A small displacement field and a calibration field that nearly undo each other's
// directions, so some round trips come home and others miss; NaN in places and a pixel
// the reverse mask leaves out.
std::vector<Output> roundTripCase(Backend& b) {
  Session s{b};
  Host w = noise(kW, kH, 2, 81, 1.5f), calibration = noise(kW, kH, 2, 82, 0.8f);
  Host reverseW = noise(kW, kH, 2, 83, 1.5f), reverseCalibration = noise(kW, kH, 2, 84, 0.8f);
  Host mask = discMask(kW, kH), reverseMask = discMask(kW, kH);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      w.at(x, y, 0) -= 1.3f;
      reverseW.at(x, y, 0) += 1.3f;
      if ((x + 5 * y) % 29 == 0) w.at(x, y, 1) = std::numeric_limits<float>::quiet_NaN();
    }
  reverseMask.at(10, 12) = 0.f;
  Buffer error = s.make(kW, kH, 1);
  b.roundTrip(error, s.put(w), s.put(calibration), s.put(reverseW), s.put(reverseCalibration), s.put(reverseMask),
              s.put(mask));
  // Three bilinear samples, float adds and a square root of errors of a few px; Vulkan may
  // fuse the samples' multiply-adds and rounds sqrt to 2.5 ulp (1.7e-5 px on lavapipe).
  return within({s.get("roundtrip_error", error)}, {5e-5, 1e-10});
}

// A textured left half and a plain right half (structure), a second image that matches the
// first where w says in the top half and not in the bottom (photometric), a falling sweep
// confidence, round-trip errors across the threshold, disparities near zero in a corner and
// depths NaN in places.
ConfidenceParams confidenceCaseParams() { return {3, 0.01f, 0.5f, 0.6f, 1.f, 1.5f, 0.3f, 0.05f, 0.f, 1.f}; }

std::vector<Output> resultConfidenceRun(Backend& b, bool optional, const ConfidenceParams& p, const std::string& tag) {
  Session s{b};
  Host image = texture(kW, kH, 91, 1), n1(kW, kH, 1), w = noise(kW, kH, 2, 92, 0.4f), mask = discMask(kW, kH);
  Host radial(kW, kH, 1), sweep(kW, kH, 1), trip(kW, kH, 1), plane(kW, kH, 1), trajectory = tangentField(kW, kH);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      if (x > kW / 2) image.at(x, y) = 0.5f + 0.001f * float(x);
      radial.at(x, y) = (x + 3 * y) % 37 == 0 ? std::numeric_limits<float>::quiet_NaN() : 2.f;
      sweep.at(x, y) = 1.2f - float(y) / float(kH - 1);
      trip.at(x, y) = (x * 7 + y * 3) % 11 == 0 ? std::numeric_limits<float>::quiet_NaN() : 0.25f * float(x % 9);
      if (x < 8 && y < 8) w.at(x, y, 0) = w.at(x, y, 1) = 0.05f;
      plane.at(x, y) = x > kW / 2 && y % 3 != 0 ? 0.2f + 0.6f * float(y) / float(kH) : 0.f;  // the plain half, filled
    }
  Host n0 = image;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) n1.at(x, y) = y < kH / 2 ? image.at(std::min(kW - 1, x + 1), y) : 1.f - image.at(x, y);
  Buffer confidence = s.make(kW, kH, 1), rb = s.put(radial), points = s.make(kW, kH, 3);
  b.fill(points, 1.f);
  b.resultConfidence(confidence, rb, points, s.put(image), s.put(n0), s.put(n1), s.put(w), s.put(trajectory),
                     optional ? s.put(sweep) : Buffer{}, optional ? s.put(trip) : Buffer{},
                     optional ? s.put(plane) : Buffer{}, s.put(mask), p);
  // Window sums in the oracle's order and the device's exp: a few ulps of values <= 1.
  return within({s.get("confidence_" + tag, confidence), s.get("confidence_radial_" + tag, rb),
                 s.get("confidence_points_" + tag, points)},
                {1e-5, 1e-12});
}

std::vector<Output> resultConfidenceCase(Backend& b) {
  return resultConfidenceRun(b, true, confidenceCaseParams(), "all");
}

std::vector<Output> resultConfidenceAloneCase(Backend& b) {
  ConfidenceParams p = confidenceCaseParams();
  p.radius = 1;
  p.infinityPx = 0.f;
  p.invalidBelow = 0.f;
  p.maxDeviationPx = 2.f;
  p.infinityBoundPx = 0.f;
  return resultConfidenceRun(b, false, p, "alone");
}

// --- the result as the user sees it ---

// Every reason a pixel is unsolved, alone: radial NaN, disparity NaN or infinite, either
// warp component NaN or infinite; and solved pixels at infinity and at a finite depth.
std::vector<Output> finishResultCase(Backend& b) {
  Session s{b};
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  Host radial = noise(kW, kH, 1, 101, 1.f), points = noise(kW, kH, 3, 102, 4.f), u = noise(kW, kH, 1, 103, 3.f);
  Host w = noise(kW, kH, 2, 104, 3.f), confidence = noise(kW, kH, 1, 105, 0.5f);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      radial.at(x, y) += 2.f;
      switch ((x + 7 * y) % 9) {
        case 0:
          radial.at(x, y) = nan;
          break;
        case 1:
          u.at(x, y) = nan;
          break;
        case 2:
          u.at(x, y) = -inf;
          break;
        case 3:
          w.at(x, y, 0) = inf;
          break;
        case 4:
          w.at(x, y, 1) = nan;
          break;
        case 5:
          radial.at(x, y) = inf, points.at(x, y, 0) = points.at(x, y, 1) = points.at(x, y, 2) = nan;
          break;
        default:
          break;
      }
    }
  Buffer valid = s.make(kW, kH, 1), z = s.make(kW, kH, 1), rb = s.put(radial), pb = s.put(points), ub = s.put(u);
  Buffer wb = s.put(w), cb = s.put(confidence);
  b.finishResult(valid, z, rb, pb, ub, wb, cb);
  // Selects and copies, no arithmetic: every backend gives the oracle's bits.
  return within(
      {s.get("finish_valid", valid), s.get("finish_z", z), s.get("finish_radial", rb), s.get("finish_points", pb),
       s.get("finish_disparity", ub), s.get("finish_warp", wb), s.get("finish_confidence", cb)},
      {0.0, 0.0});
}

}  // namespace cs::golden
