// The discrete operators of the energy on the masked grid, shared by the primal-dual
// kernel and the tests: forward-difference gradient (zero across image and mask
// borders: Neumann), its exact negative adjoint div (Dirichlet), and the data-term prox.
#pragma once
#include "cpu_views.hpp"

namespace cs::cpu {

inline float gradX(const View& f, const View& mask, int x, int y, int c = 0) {
  return linkX(mask, x, y) ? f.at(x + 1, y, c) - f.at(x, y, c) : 0.f;
}
inline float gradY(const View& f, const View& mask, int x, int y, int c = 0) {
  return linkY(mask, x, y) ? f.at(x, y + 1, c) - f.at(x, y, c) : 0.f;
}

// div = -grad^T for the vector field (fx(i, j), fy(i, j)) given as functions of the pixel.
template <class FieldX, class FieldY>
float divergence(const View& mask, int x, int y, FieldX fx, FieldY fy) {
  float d = 0.f;
  if (linkX(mask, x, y)) d += fx(x, y);
  if (linkX(mask, x - 1, y)) d -= fx(x - 1, y);
  if (linkY(mask, x, y)) d += fy(x, y);
  if (linkY(mask, x, y - 1)) d -= fy(x, y - 1);
  return d;
}

// argmin_u (u - uHat)^2 / (2 tau) + lambda |iz + (u - u0) iu|, with tauLambda = tau * lambda:
// the pointwise thresholding of the linearised L1 data term.
inline float dataProx(float uHat, float u0, float iu, float iz, float tauLambda) {
  float rho = iz + (uHat - u0) * iu;
  float threshold = tauLambda * iu * iu;
  if (rho < -threshold) return uHat + tauLambda * iu;
  if (rho > threshold) return uHat - tauLambda * iu;
  if (iu == 0.f) return uHat;  // no data term here
  return uHat - rho / iu;
}

}  // namespace cs::cpu
