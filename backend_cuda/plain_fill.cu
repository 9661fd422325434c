// Plain regions (cpu/plain_fill.cpp, backend.hpp plainSupport, fillPlanes): the most
// confident pixel under each coarse pixel, and the host's planes written into level 0's
// estimate, in the oracle's double precision for the camera.
#include "camera_models.cuh"

namespace cs::cudak {

namespace {

struct T3 {
  double v[3];
};

// The coarse pixel a full-resolution one falls in: integer arithmetic, as the oracle.
__device__ __forceinline__ int coarseOf(int X, int coarse, int full) {
  return int(((2LL * X + 1) * coarse) / (2LL * full));
}

__device__ int blockStart(int c, int coarse, int full) {
  int X = max(0, int((long long)c * full / coarse) - 1);
  while (X < full && coarseOf(X, coarse, full) < c) ++X;
  return X;
}

// The oracle's windowVariance: the same sums in the same order, no fused multiply-adds.
__device__ float windowVariance(const Img& image, const Img& mask, int x, int y) {
  constexpr int r = 2;
  if (!masked(mask, x, y)) return -1.f;
  float n = 0.f, sum = 0.f;
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx)
      if (masked(mask, x + dx, y + dy)) n = __fadd_rn(n, 1.f), sum = __fadd_rn(sum, at(image, x + dx, y + dy));
  if (n < 13.f) return -1.f;
  const float mean = __fdiv_rn(sum, n);
  float squares = 0.f;
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx)
      if (masked(mask, x + dx, y + dy)) {
        const float d = __fsub_rn(at(image, x + dx, y + dy), mean);
        squares = __fadd_rn(squares, __fmul_rn(d, d));
      }
  return __fdiv_rn(squares, n);
}

__global__ void plainSupportKernel(Img support, Img confidence, Img w, Img mask, Img levelImage, Img levelMask) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= support.width || y >= support.height) return;
  float best[5] = {0.f, 0.f, 0.f, 0.f, -1.f};
  const int X0 = blockStart(x, support.width, mask.width), Y0 = blockStart(y, support.height, mask.height);
  for (int Y = Y0; Y < mask.height && coarseOf(Y, support.height, mask.height) == y; ++Y)
    for (int X = X0; X < mask.width && coarseOf(X, support.width, mask.width) == x; ++X) {
      const float c = at(confidence, X, Y);
      if (!masked(mask, X, Y) || !(c > best[4])) continue;
      best[0] = float(X), best[1] = float(Y), best[2] = at(w, X, Y, 0), best[3] = at(w, X, Y, 1), best[4] = c;
    }
  for (int k = 0; k < 5; ++k) at(support, x, y, k) = best[k];
  at(support, x, y, 5) = windowVariance(levelImage, levelMask, x, y);
}

__global__ void fillPlanesKernel(Img u, Img w, Img planeConfidence, Img labels, Img planes, Img mask, CameraParams cam,
                                 T3 t) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= u.width || y >= u.height) return;
  at(planeConfidence, x, y) = 0.f;
  if (!masked(mask, x, y)) return;
  const int lx = coarseOf(x, labels.width, u.width), ly = coarseOf(y, labels.height, u.height);
  const float label = at(labels, lx, ly, 0);
  const long long planeCount = (long long)planes.width * planes.height / 3;
  if (!(label >= 0.f) || (long long)label >= planeCount) return;
  const int i = 3 * int(label);
  V3 ray;
  if (!cameraUnproject(cam, double(x), double(y), ray)) return;
  const double q =
      double(planes.data[i]) * ray.x + double(planes.data[i + 1]) * ray.y + double(planes.data[i + 2]) * ray.z;
  V2 px;
  if (!(q >= 0.0) || !cameraProject(cam, V3{ray.x + q * t.v[0], ray.y + q * t.v[1], ray.z + q * t.v[2]}, px)) return;
  storeWarp(u, w, px, x, y);
  at(planeConfidence, x, y) = at(labels, lx, ly, 1);
}

}  // namespace

cudaError_t launchPlainSupport(cudaStream_t s, Img support, Img confidence, Img w, Img mask, Img levelImage,
                               Img levelMask) {
  const dim3 block(16, 8);
  CS_LAUNCH(plainSupportKernel, grid2d(support.width, support.height, block), block, 0, s, support, confidence, w, mask,
            levelImage, levelMask);
  return cudaGetLastError();
}

cudaError_t launchFillPlanes(cudaStream_t s, Img u, Img w, Img planeConfidence, Img labels, Img planes, Img mask,
                             const CameraParams& cam0, const double tPrime[3]) {
  const dim3 block(16, 8);
  const T3 t{{tPrime[0], tPrime[1], tPrime[2]}};
  CS_LAUNCH(fillPlanesKernel, grid2d(u.width, u.height, block), block, 0, s, u, w, planeConfidence, labels, planes,
            mask, cam0, t);
  return cudaGetLastError();
}

}  // namespace cs::cudak
