#version 460
#extension GL_GOOGLE_include_directive : require
// The left-right round trip of the final result (backend_cpu/round_trip.cpp, backend.hpp
// roundTrip): x into image 1 by this solve's w and the calibration field, back into image 0
// by the other direction's; error = |z - x|, NaN where a step leaves its image or lands
// outside the other solve's mask.
#include "common.glsl"
#include "sampling.glsl"

layout(push_constant) uniform PC {
  FBuf error, w, calibration, reverseW, reverseCalibration, reverseMask, mask;
  int width, height, reverseWidth, reverseHeight;
} pc;

bool insideImage(int w, int h, float x, float y) { return x >= 0.0 && y >= 0.0 && x <= float(w - 1) && y <= float(h - 1); }

float roundTripAt(int x, int y) {
  const int i = y * pc.width + x;
  const float ax = float(x) + pc.w.v[2 * i], ay = float(y) + pc.w.v[2 * i + 1];
  if (!insideImage(pc.width, pc.height, ax, ay)) return quietNaN();
  const float yx = ax + sampleBilinear(pc.calibration, pc.width, pc.height, 2, 0, ax, ay);
  const float yy = ay + sampleBilinear(pc.calibration, pc.width, pc.height, 2, 1, ax, ay);
  const int rw = pc.reverseWidth, rh = pc.reverseHeight;
  if (!insideImage(rw, rh, yx, yy)) return quietNaN();
  if (pc.reverseMask.v[int(floor(yy + 0.5)) * rw + int(floor(yx + 0.5))] == 0.0) return quietNaN();
  const float bx = yx + sampleBilinear(pc.reverseW, rw, rh, 2, 0, yx, yy);
  const float by = yy + sampleBilinear(pc.reverseW, rw, rh, 2, 1, yx, yy);
  if (!insideImage(rw, rh, bx, by)) return quietNaN();
  const float zx = bx + sampleBilinear(pc.reverseCalibration, rw, rh, 2, 0, bx, by);
  const float zy = by + sampleBilinear(pc.reverseCalibration, rw, rh, 2, 1, bx, by);
  const float e = sqrt((zx - float(x)) * (zx - float(x)) + (zy - float(y)) * (zy - float(y)));
  return isnan(e) || isinf(e) ? quietNaN() : e;
}

void main() {
  const int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.width || y >= pc.height) return;
  pc.error.v[y * pc.width + x] = masked(pc.mask, pc.width, pc.height, x, y) ? roundTripAt(x, y) : quietNaN();
}
