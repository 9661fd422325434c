// Per rig / per pose: valid mask, calibration and trajectory fields in double precision
// (core/src/fields.cpp fieldsAtPixel), so a moving camera can update them per frame.
#include "camera_models.cuh"

namespace cs::cudak {

namespace {

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

// The ray lies farther than halfFov from its camera's optical axis (z); off without a limit.
__device__ bool beyondFov(const V3& ray, const FieldsParams& p) {
  return p.maxFovDeg > 0 && atan2(sqrt(ray.x * ray.x + ray.y * ray.y), ray.z) > 0.5 * p.maxFovDeg * kDegToRad;
}

__global__ void fieldsKernel(Img mask, Img calibration, Img trajectory, FieldsParams p, FieldsBaseline b) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= mask.width || y >= mask.height) return;
  bool valid = false;
  float cx = 0.f, cy = 0.f, tx = 0.f, ty = 0.f;
  V3 ray;
  do {
    if (!cameraUnproject(p.cam0, double(x), double(y), ray)) break;
    if (beyondFov(ray, p)) break;
    const double c = fabs(ray.x * b.direction[0] + ray.y * b.direction[1] + ray.z * b.direction[2]);
    if (acos(fmin(1.0, c)) < p.epipoleDeg * kDegToRad) break;
    const V3 r1{p.R[0] * ray.x + p.R[1] * ray.y + p.R[2] * ray.z, p.R[3] * ray.x + p.R[4] * ray.y + p.R[5] * ray.z,
                p.R[6] * ray.x + p.R[7] * ray.y + p.R[8] * ray.z};
    if (beyondFov(r1, p)) break;  // camera 1's field of view too
    V2 px1;
    if (!cameraProject(p.cam1, r1, px1)) break;
    if (!(px1.x >= -0.5 && px1.y >= -0.5 && px1.x <= p.cam1.width - 0.5 && px1.y <= p.cam1.height - 0.5)) break;
    V2 proj;
    J23 J;
    if (!cameraProject(p.cam0, ray, proj, &J)) break;
    double gx = J.m[0][0] * b.tPrime[0] + J.m[0][1] * b.tPrime[1] + J.m[0][2] * b.tPrime[2];
    double gy = J.m[1][0] * b.tPrime[0] + J.m[1][1] * b.tPrime[1] + J.m[1][2] * b.tPrime[2];
    const double n = sqrt(gx * gx + gy * gy);
    if (!(n > 1e-12)) break;
    gx /= n;
    gy /= n;
    valid = true;
    cx = float(px1.x - x);
    cy = float(px1.y - y);
    tx = float(gx);
    ty = float(gy);
  } while (false);
  at(mask, x, y) = valid && at(mask, x, y) != 0.f ? 1.f : 0.f;
  at(calibration, x, y, 0) = cx;
  at(calibration, x, y, 1) = cy;
  at(trajectory, x, y, 0) = tx;
  at(trajectory, x, y, 1) = ty;
}

}  // namespace

cudaError_t launchFields(cudaStream_t s, Img mask, Img calibration, Img trajectory, const FieldsParams& p,
                         const FieldsBaseline& baseline) {
  const dim3 block(16, 8);
  CS_LAUNCH(fieldsKernel, grid2d(mask.width, mask.height, block), block, 0, s, mask, calibration, trajectory, p,
            baseline);
  return cudaGetLastError();
}

}  // namespace cs::cudak
