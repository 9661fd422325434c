// The primal-dual buffers and the masked-grid operators of backend_cpu/operators.hpp.
#ifndef CS_PRIMAL_DUAL_GLSL
#define CS_PRIMAL_DUAL_GLSL
#include "common.glsl"

// Forward differences, zero across image and mask borders (Neumann).
float gradX(FBuf f, FBuf mask, int w, int h, int nc, int x, int y, int c) {
  return linkX(mask, w, h, x, y) ? f.v[idx(w, nc, x + 1, y, c)] - f.v[idx(w, nc, x, y, c)] : 0.0;
}
float gradY(FBuf f, FBuf mask, int w, int h, int nc, int x, int y, int c) {
  return linkY(mask, w, h, x, y) ? f.v[idx(w, nc, x, y + 1, c)] - f.v[idx(w, nc, x, y, c)] : 0.0;
}

// argmin_u (u - uHat)^2 / (2 tau) + lambda |iz + (u - u0) iu| (operators.hpp dataProx).
float dataProx(float uHat, float u0, float iu, float iz, float tauLambda) {
  float rho = iz + (uHat - u0) * iu;
  float threshold = tauLambda * iu * iu;
  if (rho < -threshold) return uHat + tauLambda * iu;
  if (rho > threshold) return uHat - tauLambda * iu;
  if (iu == 0.0) return uHat;
  return uHat - rho / iu;
}

#endif
