// The anisotropic diffusion tensor of I0 and the diagonal preconditioner
// (cpu/structure_tensor.cpp): separable Gaussian blur (rows, then columns), then one
// kernel that writes the tensor and the step sizes; the steps need the tensor of the
// left and upper neighbours, which that kernel recomputes (the same arithmetic, so the
// same values) instead of reading them back.
#include "common.cuh"

namespace cs::cudak {

namespace {

__global__ void blurRowsKernel(float* out, const float* image, int w, int h, TensorTaps p) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= w || y >= h) return;
  const float* row = image + size_t(y) * w;
  if (p.radius < 0) {
    out[size_t(y) * w + x] = row[x];
    return;
  }
  float s = 0.f;
  for (int i = -p.radius; i <= p.radius; ++i) s += p.taps[i + p.radius] * __ldg(&row[min(max(x + i, 0), w - 1)]);
  out[size_t(y) * w + x] = s;
}

__global__ void blurColumnsKernel(float* out, const float* rows, int w, int h, TensorTaps p) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= w || y >= h) return;
  if (p.radius < 0) {
    out[size_t(y) * w + x] = rows[size_t(y) * w + x];
    return;
  }
  float s = 0.f;
  for (int i = -p.radius; i <= p.radius; ++i)
    s += p.taps[i + p.radius] * __ldg(&rows[size_t(min(max(y + i, 0), h - 1)) * w + x]);
  out[size_t(y) * w + x] = s;
}

struct Tensor {
  float d11, d12, d22;
};

__device__ Tensor tensorAt(const float* smooth, int w, int h, int x, int y, const TensorParams& p) {
  auto at = [&](int i, int j) { return __ldg(&smooth[size_t(min(max(j, 0), h - 1)) * w + min(max(i, 0), w - 1)]); };
  const float gx = 0.5f * (at(x + 1, y) - at(x - 1, y));
  const float gy = 0.5f * (at(x, y + 1) - at(x, y - 1));
  const float mag = sqrtf(gx * gx + gy * gy);
  const float weight = fmaxf(expf(-p.beta * powf(mag, p.eta)), p.wMin);
  const float nx = mag > 1e-12f ? gx / mag : 1.f, ny = mag > 1e-12f ? gy / mag : 0.f;
  return {weight * nx * nx + ny * ny, (weight - 1.f) * nx * ny, weight * ny * ny + nx * nx};
}

__global__ void tensorStepsKernel(Img tensor, Img steps, const float* smooth, Img mask, TensorParams p) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  const int w = tensor.width, h = tensor.height;
  if (x >= w || y >= h) return;
  const Tensor d = tensorAt(smooth, w, h, x, y, p);
  reinterpret_cast<float4*>(tensor.data)[size_t(y) * w + x] = make_float4(d.d11, d.d12, d.d22, 0.f);

  const bool ex = linkX(mask, x, y), ey = linkY(mask, x, y);
  const bool exLeft = linkX(mask, x - 1, y), eyUp = linkY(mask, x, y - 1);
  // Column sum of |K| for u (columnSumU): own p rows plus the left and upper neighbours'.
  const float own = fabsf((ex ? d.d11 : 0.f) + (ey ? d.d12 : 0.f)) + fabsf((ex ? d.d12 : 0.f) + (ey ? d.d22 : 0.f));
  float left = 0.f, up = 0.f;
  if (exLeft) {
    const Tensor l = tensorAt(smooth, w, h, x - 1, y, p);
    left = fabsf(l.d11) + fabsf(l.d12);
  }
  if (eyUp) {
    const Tensor u = tensorAt(smooth, w, h, x, y - 1, p);
    up = fabsf(u.d12) + fabsf(u.d22);
  }
  const float column = own + left + up;
  const int links = int(ex) + int(ey) + int(exLeft) + int(eyUp);
  const float kFloor = 1e-2f;
  // Row sums of |K| for the two p rows (rowSumP1 / rowSumP2).
  const float r11 = ex ? d.d11 : 0.f, r12 = ey ? d.d12 : 0.f;
  const float rowP1 = fabsf(r11 + r12) + fabsf(r11) + fabsf(r12);
  const float s12 = ex ? d.d12 : 0.f, s22 = ey ? d.d22 : 0.f;
  const float rowP2 = fabsf(s12 + s22) + fabsf(s12) + fabsf(s22);
  reinterpret_cast<float4*>(steps.data)[size_t(y) * w + x] =
      make_float4(1.f / (p.alpha1 * fmaxf(column, kFloor)), 1.f / (p.alpha1 + p.alpha0 * float(links)),
                  1.f / (p.alpha1 * (rowP1 + 1.f)), 1.f / (p.alpha1 * (rowP2 + 1.f)));
}

}  // namespace

cudaError_t launchStructureTensor(cudaStream_t s, Img tensor, Img steps, Img image, Img mask, const TensorParams& p,
                                  const TensorTaps& taps, float* tmpRows, float* tmpSmooth) {
  const dim3 block(32, 8), grid = grid2d(image.width, image.height, block);
  CS_LAUNCH(blurRowsKernel, grid, block, 0, s, tmpRows, image.data, image.width, image.height, taps);
  CS_LAUNCH(blurColumnsKernel, grid, block, 0, s, tmpSmooth, tmpRows, image.width, image.height, taps);
  CS_LAUNCH(tensorStepsKernel, grid, block, 0, s, tensor, steps, tmpSmooth, mask, p);
  return cudaGetLastError();
}

}  // namespace cs::cudak
