// A state (inverse depth and its variance) moved into the next frame's view: a sequence's
// warm start and the temporal filter's prior (cpu/carry_estimate.cpp, backend.hpp
// carryEstimate). A gather, one thread a destination pixel, in double precision like the
// oracle, its sums in the order Eigen evaluates the oracle's (3.4, SSE2, no contraction).
// The motion is read from its device buffer, so a recorded frame uses each frame's upload.
#include "camera_models.cuh"

namespace cs::cudak {

namespace {

struct Sample {
  float q, v;
  V3 ray;
  bool found;
};

// The state at the src pixel nearest to the projection of direction d (the oracle's lookUp).
__device__ Sample lookUp(const Img& src, const CameraParams& cam, const V3& d) {
  Sample s{-1.f, 0.f, {0, 0, 0}, false};
  V2 px;
  if (!cameraProject(cam, d, px)) return s;
  const double nx = floor(px.x + 0.5 - kCarryTie), ny = floor(px.y + 0.5 - kCarryTie);
  if (!(nx >= 0 && ny >= 0 && nx < src.width && ny < src.height)) return s;
  const int ix = int(nx), iy = int(ny);
  s.q = at(src, ix, iy, 0);
  s.v = at(src, ix, iy, 1);
  s.found = s.q >= 0.f && cameraUnproject(cam, double(ix), double(iy), s.ray);
  return s;
}

__global__ void carryEstimateKernel(Img dst, Img src, Img guess, const float* motion, Img mask, CarryParams p) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= dst.width || y >= dst.height) return;
  float qOut = -1.f, vOut = 0.f;
  V3 ray;
  if (masked(mask, x, y) && cameraUnproject(p.dstCam, double(x), double(y), ray)) {
    // R (row-major) and T = t + extraT, as the oracle builds them from the floats.
    double R[9];
#pragma unroll
    for (int i = 0; i < 9; ++i) R[i] = double(__ldg(motion + i));
    const double T[3] = {double(__ldg(motion + 9)) + p.extraT[0], double(__ldg(motion + 10)) + p.extraT[1],
                         double(__ldg(motion + 11)) + p.extraT[2]};
    double q = 0;
    bool start = true;
    if (guess.data) {
      const float radial = at(guess, x, y);
      if (isnan(radial) || radial <= 0.f)
        start = false;
      else
        q = isinf(radial) ? 0.0 : 1.0 / double(radial);
    } else {
      const Sample s = lookUp(src, p.srcCam, ray);
      start = s.found;
      q = s.q;
    }
    if (start) {
      Sample s{-1.f, 0.f, {0, 0, 0}, false};
      for (int k = 0; k < p.iterations; ++k) {
        // R^T (ray - q T): each component summed first to last.
        const V3 a{ray.x - q * T[0], ray.y - q * T[1], ray.z - q * T[2]};
        const V3 d{(R[0] * a.x + R[3] * a.y) + R[6] * a.z, (R[1] * a.x + R[4] * a.y) + R[7] * a.z,
                   (R[2] * a.x + R[5] * a.y) + R[8] * a.z};
        s = lookUp(src, p.srcCam, d);
        if (!s.found) break;
        // R ray_s + q_s T: Eigen sums the first two rows first to last (one packet) and the
        // third from the last pair (its scalar tail); the norm first to last.
        const double qs = s.q;
        const V3 r = s.ray;
        const V3 n{((R[0] * r.x + R[1] * r.y) + R[2] * r.z) + qs * T[0],
                   ((R[3] * r.x + R[4] * r.y) + R[5] * r.z) + qs * T[1],
                   (R[6] * r.x + (R[7] * r.y + R[8] * r.z)) + qs * T[2]};
        q = qs / sqrt((n.x * n.x + n.y * n.y) + n.z * n.z);
      }
      if (s.found) {
        qOut = float(q);
        vOut = s.v;
      }
    }
  }
  at(dst, x, y, 0) = qOut;
  at(dst, x, y, 1) = vOut;
}

}  // namespace

cudaError_t launchCarryEstimate(cudaStream_t s, Img dst, Img src, Img guess, const float* motion, Img mask,
                                const CarryParams& p) {
  const dim3 block(16, 8);
  CS_LAUNCH(carryEstimateKernel, grid2d(dst.width, dst.height, block), block, 0, s, dst, src, guess, motion, mask, p);
  return cudaGetLastError();
}

}  // namespace cs::cudak
