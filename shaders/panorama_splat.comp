#version 460
#extension GL_GOOGLE_include_directive : require
// One pass of one camera's placed pixels into the panorama's accumulator
// (backend_cpu/panorama.cpp panoramaSplat, backend.hpp): each pixel's footprint box, by
// pc.pass the best confidence, the nearest inverse range or the sums. Pixels overlap, so
// the updates are core 32-bit atomics on the floats' bits: atomicMax where the values are
// >= 0 (their order is their bits'), a compare-and-swap loop for the float sums; or, with
// CS_ATOMIC_FLOAT_ADD (where the device has shaderBufferFloat32AtomicAdd), a native float
// atomicAdd for the sums, which spares the loop's retries under contention.
#ifdef CS_ATOMIC_FLOAT_ADD
#extension GL_EXT_shader_atomic_float : require
#endif
#include "common.glsl"

// The accumulator's floats as their bits (the same address as an FBuf).
layout(buffer_reference, std430, buffer_reference_align = 4) buffer UBuf { uint v[]; };

layout(push_constant) uniform PC {
  UBuf accum;  // 6 floats per panorama pixel: see backend.hpp panoramaSplat
  FBuf place, confidence, grey;  // grey: place when absent
  int width, height;             // the camera's grid
  int panoWidth;                 // W; the panorama's rows W / 2
  int pass;                      // PanoramaPass
  int hasGrey;
  float minConfidence;
  float agreement;  // kPanoramaAgreement
} pc;

// PanoramaPass (kernel_params.hpp).
const int kBest = 0, kNearest = 1;

float load(uint k) { return uintBitsToFloat(pc.accum.v[k]); }

// value > 0 (so not NaN): larger floats have larger bits, and the accumulator starts at 0.
void maxInto(uint k, float value) {
  if (value > 0.0) atomicMax(pc.accum.v[k], floatBitsToUint(value));
}

#ifdef CS_ATOMIC_FLOAT_ADD
void addInto(uint k, float value) { atomicAdd(FBuf(pc.accum).v[k], value); }
#else
void addInto(uint k, float value) {
  uint seen = pc.accum.v[k];
  for (;;) {
    const uint sum = floatBitsToUint(uintBitsToFloat(seen) + value);
    const uint before = atomicCompSwap(pc.accum.v[k], seen, sum);
    if (before == seen) break;
    seen = before;
  }
}
#endif

void main() {
  const int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.width || y >= pc.height) return;
  const int i = y * pc.width + x;
  const float col = pc.place.v[5 * i], row = pc.place.v[5 * i + 1];
  const float hx = pc.place.v[5 * i + 2], hy = pc.place.v[5 * i + 3], range = pc.place.v[5 * i + 4];
  const float conf = pc.confidence.v[i];
  if (isnan(col) || (pc.minConfidence > 0.0 && !(conf >= pc.minConfidence))) return;
  const bool finiteConf = !isnan(conf) && !isinf(conf);
  const float c = finiteConf ? conf : 0.0;
  const float w = finiteConf ? max(conf, 1e-6) : 1e-6;
  const float g = pc.hasGrey != 0 ? pc.grey.v[i] : quietNaN();
  const bool hasG = !isnan(g) && !isinf(g);
  precise float inverse = 1.0 / range;
  precise float weighted = w * inverse;  // as the oracle: w (1 / range), not w / range
  precise float wg = w * g;
  const int W = pc.panoWidth, H = pc.panoWidth / 2;
  precise float left = col - hx, right = col + hx, top = row - hy, bottom = row + hy;
  const int x0 = int(ceil(left)), x1 = int(floor(right));
  const int y0 = max(0, int(ceil(top))), y1 = min(H - 1, int(floor(bottom)));
  for (int py = y0; py <= y1; ++py)
    for (int px = x0; px <= x1; ++px) {
      // px >= -W (hx <= W / 2): px + W is not negative, where GLSL's % is undefined.
      const uint k = 6u * (uint(py) * uint(W) + uint(px + W) % uint(W));  // past 2^31 at the widest
      if (pc.pass == kBest) {
        maxInto(k, c);
        continue;
      }
      precise float halfBest = 0.5 * load(k);
      if (!(c >= halfBest)) continue;
      if (pc.pass == kNearest) {
        maxInto(k + 1u, inverse);
        continue;
      }
      const float nearest = load(k + 1u);
      precise float gap = abs(inverse - nearest);
      precise float tolerance = pc.agreement * max(inverse, nearest);
      if (!(gap <= tolerance)) continue;
      addInto(k + 2u, weighted);
      addInto(k + 3u, w);
      if (hasG) {
        addInto(k + 4u, wg);
        addInto(k + 5u, w);
      }
    }
}
