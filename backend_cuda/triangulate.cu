// Depth from the warp (core/src/triangulate.cpp triangulateRadial, in double precision):
// rays from camera 0 and from the rotation-compensated camera 1 at -t'.
#include "camera_models.cuh"

namespace cs::cudak {

namespace {

struct T3 {
  double v[3];
};

__device__ __forceinline__ V3 cross(const V3& a, const V3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
__device__ __forceinline__ double dot(const V3& a, const V3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

__global__ void triangulateKernel(Img radial, Img points, Img w, Img mask, CameraParams cam0, T3 tPrime) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= radial.width || y >= radial.height) return;
  const float nan = __int_as_float(0x7fc00000);
  float rOut = nan, px = nan, py = nan, pz = nan;
  if (at(mask, x, y) != 0.f) {
    const double wx = at(w, x, y, 0), wy = at(w, x, y, 1);
    V3 d0, d1;
    double r;
    if (!cameraUnproject(cam0, double(x), double(y), d0) || !cameraUnproject(cam0, x + wx, y + wy, d1)) {
      r = nan;
    } else {
      const V3 c1{-tPrime.v[0], -tPrime.v[1], -tPrime.v[2]};
      const V3 n = cross(d0, d1);
      const double n2 = dot(n, n);
      if (n2 < 1e-24) {
        r = __longlong_as_double(0x7ff0000000000000LL);
      } else {
        const double a = dot(cross(c1, d1), n) / n2;
        const double b = dot(cross(c1, d0), n) / n2;
        r = (!(a > 0) || !(b > 0)) ? __longlong_as_double(0x7ff0000000000000LL) : a;
      }
    }
    V3 ray;
    if (!isnan(r) && cameraUnproject(cam0, double(x), double(y), ray)) {
      rOut = float(r);
      if (isfinite(r)) {
        px = float(r * ray.x);
        py = float(r * ray.y);
        pz = float(r * ray.z);
      }
    }
  }
  at(radial, x, y) = rOut;
  at(points, x, y, 0) = px;
  at(points, x, y, 1) = py;
  at(points, x, y, 2) = pz;
}

}  // namespace

cudaError_t launchTriangulate(cudaStream_t s, Img radial, Img points, Img w, Img mask, const CameraParams& cam0,
                              const double tPrime[3]) {
  const dim3 block(16, 8);
  const T3 t{{tPrime[0], tPrime[1], tPrime[2]}};
  CS_LAUNCH(triangulateKernel, grid2d(radial.width, radial.height, block), block, 0, s, radial, points, w, mask, cam0,
            t);
  return cudaGetLastError();
}

}  // namespace cs::cudak
