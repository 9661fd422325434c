#version 460
#extension GL_GOOGLE_include_directive : require
// The final result's confidence (backend_cpu/result_confidence.cpp, backend.hpp
// resultConfidence): structure along the epipolar curve x photometric agreement x the
// sweep's consistency x the round trip; then the invalid pixels and the points at infinity.
// Its second pass: the first (result_confidence_terms.comp) left each pixel's terms.
#include "common.glsl"

// Mirrors VkConfidenceParams in backend_vulkan/kernels.cpp.
layout(buffer_reference, std430, buffer_reference_align = 4) buffer ConfidenceParamsRef {
  int radius;
  float noise, sigmaPx, residualScale, roundTripPx, roundTripMaxPx, infinityPx, invalidBelow, maxDeviationPx;
  float infinityBoundPx;
};

layout(push_constant) uniform PC {
  FBuf confidence, radial, points, terms, w, trajectory, sweepConfidence, roundTripError, planeConfidence, mask;
  ConfidenceParamsRef prm;
  int width, height, hasSweep, hasRoundTrip, hasPlane;
} pc;

bool m(int x, int y) { return masked(pc.mask, pc.width, pc.height, x, y); }

// The window's sums of the first pass's terms (result_confidence_terms.comp), in the
// oracle's order (rows, then columns): the structure along the epipolar curve and the
// photometric agreement.
vec2 windowTerms(int x, int y, int r) {
  const int i = y * pc.width + x;
  const float gx = pc.trajectory.v[2 * i], gy = pc.trajectory.v[2 * i + 1];
  float s = 0.0, sum = 0.0;
  int count = 0;
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx) {
      const int cx = x + dx, cy = y + dy;
      if (cx < 0 || cy < 0 || cx >= pc.width || cy >= pc.height) continue;
      const int c = 4 * (cy * pc.width + cx);
      const int flags = int(pc.terms.v[c + 3]);
      if ((flags & 1) != 0) {
        const float along = gx * pc.terms.v[c] + gy * pc.terms.v[c + 1];
        s += along * along;
      }
      if ((flags & 2) != 0) {
        sum += pc.terms.v[c + 2];
        ++count;
      }
    }
  const float signal = s * pc.prm.sigmaPx * pc.prm.sigmaPx;
  const float structure = signal / (signal + 2.0 * pc.prm.noise * pc.prm.noise);
  const float q = sum / float(max(count, 1)) / pc.prm.residualScale;
  return vec2(structure, count == 0 ? 0.0 : exp(-q * q));
}

// backend_cpu/result_confidence.cpp farBelowBound: |w| < 2 deviations, |w| + 2 deviations <= bound.
bool farBelowBound(float w2, float structure, float sigmaPx, float bound) {
  precise float b = 4.0 * sigmaPx * sigmaPx * (1.0 - structure);
  precise float rest = bound * bound * structure - w2 * structure - b;
  precise float lhs = 4.0 * w2 * b * structure;
  precise float rhs = rest * rest;
  precise float signal = w2 * structure;
  return signal < b && rest >= 0.0 && lhs <= rhs;
}

void main() {
  const int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.width || y >= pc.height) return;
  const int i = y * pc.width + x;
  pc.confidence.v[i] = 0.0;
  if (!m(x, y) || isnan(pc.radial.v[i])) return;
  const int r = pc.prm.radius;
  const vec2 terms = windowTerms(x, y, r);
  const float structure = pc.hasPlane != 0 ? max(terms.x, pc.planeConfidence.v[i]) : terms.x;
  float c = structure * terms.y;
  if (pc.hasSweep != 0) {
    float sweep = min(1.0, max(0.0, pc.sweepConfidence.v[i]));
    if (pc.hasPlane != 0) sweep = max(sweep, pc.planeConfidence.v[i]);
    c *= sweep;
  }
  bool invalid = false;
  if (pc.hasRoundTrip != 0) {
    const float e = pc.roundTripError.v[i];
    invalid = isnan(e) || (pc.prm.roundTripMaxPx > 0.0 && e > pc.prm.roundTripMaxPx);
    const float q = e / pc.prm.roundTripPx;
    c *= invalid ? 0.0 : exp(-q * q);
  }
  const float ratio = pc.prm.maxDeviationPx / pc.prm.sigmaPx;
  const bool unobservable = pc.prm.maxDeviationPx > 0.0 && structure < 1.0 / (1.0 + ratio * ratio);
  if (invalid || unobservable || c < pc.prm.invalidBelow) {
    pc.radial.v[i] = quietNaN();
    for (int k = 0; k < 3; ++k) pc.points.v[3 * i + k] = quietNaN();
    return;
  }
  pc.confidence.v[i] = c;
  const float wx = pc.w.v[2 * i], wy = pc.w.v[2 * i + 1];
  precise float w2 = wx * wx + wy * wy;
  if (w2 < pc.prm.infinityPx * pc.prm.infinityPx ||
      (pc.prm.infinityBoundPx > 0.0 && farBelowBound(w2, structure, pc.prm.sigmaPx, pc.prm.infinityBoundPx))) {
    pc.radial.v[i] = posInf();
    for (int k = 0; k < 3; ++k) pc.points.v[3 * i + k] = quietNaN();
  }
}
