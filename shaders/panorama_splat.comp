#version 460
#extension GL_GOOGLE_include_directive : require
// One pass of one camera's placed pixels into the panorama's accumulator
// (backend_cpu/panorama.cpp panoramaSplat, backend.hpp): each pixel's footprint box, by
// pc.pass the best confidence, the nearest inverse range or the sums. Pixels overlap, so
// the updates are core 32-bit atomics on the floats' bits: atomicMax where the values are
// >= 0 (their order is their bits'), a compare-and-swap loop for the float sums; or, with
// CS_ATOMIC_FLOAT_ADD (where the device has shaderBufferFloat32AtomicAdd), a native float
// atomicAdd for the sums, which spares the loop's retries under contention.
//
// Near the poles a footprint spans up to half the panorama's columns, so a few invocations
// would loop thousands of times while the rest of their subgroup waits. With CS_SUBGROUP
// (where the device has subgroup ballots in compute shaders) a box of at most kOwnArea
// pixels stays its own invocation's work and each larger one is shared out over the
// subgroup (as backend_cuda/panorama.cu's warps): only the atomics' order changes, and
// the sums' results are order-independent up to rounding, the maxima exactly.
#ifdef CS_ATOMIC_FLOAT_ADD
#extension GL_EXT_shader_atomic_float : require
#endif
#ifdef CS_SUBGROUP
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require
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
  float parallaxSlack;
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

// A camera pixel's footprint: columns x0 .. x0 + columns - 1 (unwrapped) of rows y0 ..
// y0 + rows - 1, and what it splats there. Empty (area 0) where the pixel is outside the
// grid or takes no part.
struct Box {
  int x0, y0, columns, rows;
  float c, w, inverse, g;  // confidence, weight (both finite), 1 / range, grey (NaN: none)
};

Box boxOf(int x, int y) {
  Box b = Box(0, 0, 0, 0, 0.0, 0.0, 0.0, 0.0);
  if (x >= pc.width || y >= pc.height) return b;
  const int i = y * pc.width + x;
  const float col = pc.place.v[5 * i], row = pc.place.v[5 * i + 1];
  const float hx = pc.place.v[5 * i + 2], hy = pc.place.v[5 * i + 3], range = pc.place.v[5 * i + 4];
  const float conf = pc.confidence.v[i];
  if (isnan(col) || (pc.minConfidence > 0.0 && !(conf >= pc.minConfidence))) return b;
  const bool finiteConf = !isnan(conf) && !isinf(conf);
  b.c = finiteConf ? conf : 0.0;
  b.w = finiteConf ? max(conf, 1e-6) : 1e-6;
  b.g = pc.hasGrey != 0 ? pc.grey.v[i] : quietNaN();
  precise float inverse = 1.0 / range;
  b.inverse = inverse;
  precise float left = col - hx, right = col + hx, top = row - hy, bottom = row + hy;
  b.x0 = int(ceil(left));
  b.y0 = max(0, int(ceil(top)));
  b.columns = max(0, int(floor(right)) - b.x0 + 1);
  b.rows = max(0, min(pc.panoWidth / 2 - 1, int(floor(bottom))) - b.y0 + 1);
  return b;
}

// Pixel k of the box, in row-major order.
void splat(Box b, int k) {
  const int W = pc.panoWidth, px = b.x0 + k % b.columns, py = b.y0 + k / b.columns;
  // px >= -W (hx <= W / 2): px + W is not negative, where GLSL's % is undefined.
  const uint k6 = 6u * (uint(py) * uint(W) + uint(px + W) % uint(W));  // past 2^31 at the widest
  if (pc.pass == kBest) {
    maxInto(k6, b.c);
    return;
  }
  precise float halfBest = 0.5 * load(k6);
  if (!(b.c >= halfBest)) return;
  if (pc.pass == kNearest) {
    maxInto(k6 + 1u, b.inverse);
    return;
  }
  const float nearest = load(k6 + 1u);
  precise float gap = abs(b.inverse - nearest);
  precise float tolerance = pc.agreement * max(b.inverse, nearest) + pc.parallaxSlack;
  if (!(gap <= tolerance)) return;
  precise float weighted = b.w * b.inverse;  // as the oracle: w (1 / range), not w / range
  addInto(k6 + 2u, weighted);
  addInto(k6 + 3u, b.w);
  if (!isnan(b.g) && !isinf(b.g)) {
    precise float wg = b.w * b.g;
    addInto(k6 + 4u, wg);
    addInto(k6 + 5u, b.w);
  }
}

// Boxes of at most this many pixels are their own invocation's work (backend_cuda's kOwnArea).
const int kOwnArea = 32;

// No invocation returns early: the subgroup operations see the whole subgroup, those
// outside the grid with an empty box.
void main() {
#ifdef CS_SUBGROUP
  // Lanes share a large box by rank among the invocations present (taken first, in
  // uniform control flow): the subgroup's size where it is full, and no pixel missed where a
  // device leaves some lanes empty.
  const uvec4 present = subgroupBallot(true);
  const int lanes = int(subgroupBallotBitCount(present)), rank = int(subgroupBallotExclusiveBitCount(present));
#endif
  const Box own = boxOf(int(gl_GlobalInvocationID.x), int(gl_GlobalInvocationID.y));
  const int area = own.columns * own.rows;
#ifndef CS_SUBGROUP
  for (int k = 0; k < area; ++k) splat(own, k);
#else
  if (area <= kOwnArea)
    for (int k = 0; k < area; ++k) splat(own, k);
  // The large boxes one at a time, lowest lane first (a uvec4: subgroups up to 128);
  // source is uniform, as subgroupBroadcast's id must be.
  for (uvec4 large = subgroupBallot(area > kOwnArea); any(notEqual(large, uvec4(0)));) {
    const uint source = subgroupBallotFindLSB(large);
    large[source / 32u] &= ~(1u << (source % 32u));
    const Box b = Box(subgroupBroadcast(own.x0, source), subgroupBroadcast(own.y0, source),
                      subgroupBroadcast(own.columns, source), subgroupBroadcast(own.rows, source),
                      subgroupBroadcast(own.c, source), subgroupBroadcast(own.w, source),
                      subgroupBroadcast(own.inverse, source), subgroupBroadcast(own.g, source));
    for (int k = rank; k < b.columns * b.rows; k += lanes) splat(b, k);
  }
#endif
}
