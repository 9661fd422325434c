// The temporal filter of a sequence: a one-state Kalman update of each pixel's inverse depth,
// gated so that a pixel whose new estimate disagrees with the carried one beyond their
// uncertainty takes the new value at once (cpu/temporal_filter.cpp, backend.hpp
// temporalFilter). One thread a pixel, in double precision like the oracle.
#include "camera_models.cuh"

namespace cs::cudak {

namespace {

// std::max's choice (the first unless it is less), NaN included.
__device__ __forceinline__ double stdMax(double a, double b) { return a < b ? b : a; }

__global__ void temporalFilterKernel(Img state, Img u, Img w, Img prior, Img radial, Img points, Img confidence,
                                     Img mask, TemporalParams p) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= state.width || y >= state.height) return;
  float qOut = -1.f, vOut = 0.f;
  const float rho = at(radial, x, y);
  V3 ray;
  V2 px;
  J23 J;
  if (masked(mask, x, y) && !isnan(rho) && cameraUnproject(p.cam, double(x), double(y), ray) &&
      cameraProject(p.cam, ray, px, &J)) {
    const double qm = isinf(rho) ? 0.0 : 1.0 / double(rho);
    // |J t'|: each row summed first to last (Eigen's packet over the two rows).
    const double gx = (J.m[0][0] * p.tPrime[0] + J.m[0][1] * p.tPrime[1]) + J.m[0][2] * p.tPrime[2];
    const double gy = (J.m[1][0] * p.tPrime[0] + J.m[1][1] * p.tPrime[1]) + J.m[1][2] * p.tPrime[2];
    const double g = sqrt(gx * gx + gy * gy);
    const double c = stdMax(double(confidence.data ? at(confidence, x, y) : 1.f), double(p.minConfidence));
    const double Rm = double(p.sigmaPx) * double(p.sigmaPx) / (c * c);
    const double qp = at(prior, x, y, 0);
    const double P = double(at(prior, x, y, 1)) + double(p.processPx) * double(p.processPx);
    const double innovation = g * (qm - qp);
    if (!(qp >= 0.0) || innovation * innovation > double(p.gate) * double(p.gate) * (P + Rm)) {
      qOut = float(qm);
      vOut = float(Rm);
    } else {
      const double K = stdMax(P / (P + Rm), 1.0 - double(p.strength));
      const double q = qp + K * (qm - qp);
      qOut = float(q);
      vOut = float((1 - K) * (1 - K) * P + K * K * Rm);
      V2 moved;
      if (p.strength != 0.f &&
          cameraProject(p.cam, V3{ray.x + q * p.tPrime[0], ray.y + q * p.tPrime[1], ray.z + q * p.tPrime[2]}, moved)) {
        storeWarp(u, w, moved, x, y);
        // The depth triangulate() would give from the new w, without a second pass.
        const float nan = __int_as_float(0x7fc00000);
        at(radial, x, y) = q > 0.0 ? float(1.0 / q) : __int_as_float(0x7f800000);
        at(points, x, y, 0) = q > 0.0 ? float(ray.x / q) : nan;
        at(points, x, y, 1) = q > 0.0 ? float(ray.y / q) : nan;
        at(points, x, y, 2) = q > 0.0 ? float(ray.z / q) : nan;
      }
    }
  }
  at(state, x, y, 0) = qOut;
  at(state, x, y, 1) = vOut;
}

}  // namespace

cudaError_t launchTemporalFilter(cudaStream_t s, Img state, Img u, Img w, Img prior, Img radial, Img points,
                                 Img confidence, Img mask, const TemporalParams& p) {
  const dim3 block(16, 8);
  CS_LAUNCH(temporalFilterKernel, grid2d(state.width, state.height, block), block, 0, s, state, u, w, prior, radial,
            points, confidence, mask, p);
  return cudaGetLastError();
}

}  // namespace cs::cudak
