#version 460
#extension GL_GOOGLE_include_directive : require
// The panorama's range, grey and confidence from the splats' accumulator
// (backend_cpu/panorama.cpp panoramaResolve, backend.hpp), which it leaves all 0 again:
// the state the next frame's splats start from.
#include "common.glsl"

layout(push_constant) uniform PC {
  FBuf range, grey, confidence, accum;
  int width, height;  // the panorama's
} pc;

void main() {
  const int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.width || y >= pc.height) return;
  const int i = y * pc.width + x;
  const uint k = 6u * uint(i);  // past 2^31 at the widest panorama
  const float best = pc.accum.v[k], weightedInverse = pc.accum.v[k + 2u], weights = pc.accum.v[k + 3u];
  const float greySum = pc.accum.v[k + 4u], greyWeights = pc.accum.v[k + 5u];
  if (!(weights > 0.0)) {
    pc.range.v[i] = quietNaN();
    pc.grey.v[i] = quietNaN();
    pc.confidence.v[i] = quietNaN();
  } else {
    pc.range.v[i] = weightedInverse == 0.0 ? posInf() : weights / weightedInverse;
    pc.confidence.v[i] = best;
    pc.grey.v[i] = greyWeights > 0.0 ? greySum / greyWeights : quietNaN();
  }
  for (uint c = 0u; c < 6u; ++c) pc.accum.v[k + c] = 0.0;
}
