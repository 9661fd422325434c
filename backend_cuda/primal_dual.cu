// One preconditioned primal-dual iteration of anisotropic TGV-L1 per launch
// (cpu/primal_dual.cpp), the dual and the primal pass fused: a block computes the new
// duals p, q (and D p) of its tile plus a one-pixel halo to the left and above into
// shared memory, then the primal update of its tile from there. The dual variables and
// the over-relaxed primals ping-pong between two buffer sets (read one, write the
// other), so a block never reads what a neighbouring block of the same launch wrote;
// u and v are only read and written at their own pixel and stay in place.
#include "common.cuh"

namespace cs::cudak {

namespace {

constexpr int kTileW = 32, kTileH = 8;
// Blocks per SM to ask registers for: all the threads an SM holds (2048 on sm_80 and
// Hopper, 1536 on sm_86/87/89, 1024 on Turing). On Hopper this caps the kernel at 32
// registers without spills and took it from 62 % to 100 % theoretical occupancy.
#if defined(__CUDA_ARCH__) && (__CUDA_ARCH__ == 800 || __CUDA_ARCH__ >= 900)
constexpr int kMinBlocks = 8;
#elif defined(__CUDA_ARCH__) && __CUDA_ARCH__ >= 860
constexpr int kMinBlocks = 6;
#else
constexpr int kMinBlocks = 4;
#endif
constexpr int kDualW = kTileW + 1, kDualH = kTileH + 1;  // tile plus the left / upper halo

__device__ __forceinline__ float dataProx(float uHat, float u0, float iu, float iz, float tauLambda) {
  const float rho = iz + (uHat - u0) * iu;
  const float threshold = tauLambda * iu * iu;
  if (rho < -threshold) return uHat + tauLambda * iu;
  if (rho > threshold) return uHat - tauLambda * iu;
  if (iu == 0.f) return uHat;
  return uHat - rho / iu;
}

__device__ __forceinline__ bool isMasked(const float* mask, int w, int h, int x, int y) {
  return x >= 0 && y >= 0 && x < w && y < h && __ldg(&mask[size_t(y) * w + x]) != 0.f;
}

enum : unsigned char { kMasked = 1, kLinkX = 2, kLinkY = 4 };

__global__ void __launch_bounds__(kTileW * kTileH, kMinBlocks) primalDualKernel(PrimalDualDev pd, StepDev step, int parity) {
  __shared__ float2 sP[kDualH][kDualW];
  __shared__ float2 sDp[kDualH][kDualW];
  __shared__ float4 sQ[kDualH][kDualW];
  __shared__ unsigned char sFlags[kDualH][kDualW];

  const int w = pd.width, h = pd.height;
  const int x0 = blockIdx.x * kTileW, y0 = blockIdx.y * kTileH;
  const int tid = threadIdx.y * kTileW + threadIdx.x;
  const float* __restrict__ uBarIn = pd.uBar[parity];
  const float2* __restrict__ vBarIn = reinterpret_cast<const float2*>(pd.vBar[parity]);
  const float2* __restrict__ pIn = reinterpret_cast<const float2*>(pd.p[parity]);
  const float4* __restrict__ qIn = reinterpret_cast<const float4*>(pd.q[parity]);
  float2* __restrict__ pOut = reinterpret_cast<float2*>(pd.p[1 - parity]);
  float4* __restrict__ qOut = reinterpret_cast<float4*>(pd.q[1 - parity]);
  const float4* __restrict__ tensor = reinterpret_cast<const float4*>(pd.tensor);
  const float4* __restrict__ steps = reinterpret_cast<const float4*>(pd.steps);
  const float alpha0 = pd.alpha0, alpha1 = pd.alpha1;

  // --- dual pass over the tile and its halo ---
  for (int k = tid; k < kDualW * kDualH; k += kTileW * kTileH) {
    const int lx = k % kDualW, ly = k / kDualW;
    const int i = x0 - 1 + lx, j = y0 - 1 + ly;
    float2 p = make_float2(0.f, 0.f);
    float4 q = make_float4(0.f, 0.f, 0.f, 0.f);
    float4 t = make_float4(0.f, 0.f, 0.f, 0.f);
    unsigned char flags = 0;
    if (i >= 0 && j >= 0 && i < w && j < h) {
      const size_t idx = size_t(j) * w + i;
      p = __ldg(&pIn[idx]);
      q = __ldg(&qIn[idx]);
      if (__ldg(&pd.mask[idx]) != 0.f) {
        const bool ex = isMasked(pd.mask, w, h, i + 1, j), ey = isMasked(pd.mask, w, h, i, j + 1);
        flags = kMasked | (ex ? kLinkX : 0) | (ey ? kLinkY : 0);
        t = __ldg(&tensor[idx]);
        const float2 sigmaP = __ldg(reinterpret_cast<const float2*>(steps + idx) + 1);
        const float ub = __ldg(&uBarIn[idx]);
        const float2 vb = __ldg(&vBarIn[idx]);
        float gx = 0.f, gy = 0.f;
        float2 vgx = make_float2(0.f, 0.f), vgy = make_float2(0.f, 0.f);
        if (ex) {
          gx = __ldg(&uBarIn[idx + 1]) - ub;
          const float2 vr = __ldg(&vBarIn[idx + 1]);
          vgx = make_float2(vr.x - vb.x, vr.y - vb.y);
        }
        if (ey) {
          gy = __ldg(&uBarIn[idx + w]) - ub;
          const float2 vd = __ldg(&vBarIn[idx + w]);
          vgy = make_float2(vd.x - vb.x, vd.y - vb.y);
        }
        const float a1 = t.x * gx + t.y * gy - vb.x;
        const float a2 = t.y * gx + t.z * gy - vb.y;
        p.x = p.x + step.sigmaScale * sigmaP.x * alpha1 * a1;
        p.y = p.y + step.sigmaScale * sigmaP.y * alpha1 * a2;
        {
          float s = 0.f;
          s += p.x * p.x;
          s += p.y * p.y;
          const float norm = sqrtf(s);
          if (norm > 1.f) {
            p.x /= norm;
            p.y /= norm;
          }
        }
        const float sigmaQ = step.sigmaScale * 0.5f / alpha0;
        q.x = q.x + sigmaQ * alpha0 * vgx.x;
        q.y = q.y + sigmaQ * alpha0 * vgy.x;
        q.z = q.z + sigmaQ * alpha0 * vgx.y;
        q.w = q.w + sigmaQ * alpha0 * vgy.y;
        {
          float s = 0.f;
          s += q.x * q.x;
          s += q.y * q.y;
          s += q.z * q.z;
          s += q.w * q.w;
          const float norm = sqrtf(s);
          if (norm > 1.f) {
            q.x /= norm;
            q.y /= norm;
            q.z /= norm;
            q.w /= norm;
          }
        }
      }
      if (lx > 0 && ly > 0) {  // the tile's own pixels: write the new (or unchanged) duals
        pOut[idx] = p;
        qOut[idx] = q;
      }
    }
    sP[ly][lx] = p;
    sQ[ly][lx] = q;
    sDp[ly][lx] = make_float2(t.x * p.x + t.y * p.y, t.y * p.x + t.z * p.y);
    sFlags[ly][lx] = flags;
  }
  __syncthreads();

  // --- primal pass over the tile ---
  const int x = x0 + threadIdx.x, y = y0 + threadIdx.y;
  if (x >= w || y >= h) return;
  const int lx = threadIdx.x + 1, ly = threadIdx.y + 1;
  const size_t idx = size_t(y) * w + x;
  float* __restrict__ uBarOut = pd.uBar[1 - parity];
  float2* __restrict__ vBarOut = reinterpret_cast<float2*>(pd.vBar[1 - parity]);
  const unsigned char f = sFlags[ly][lx];
  if (!(f & kMasked)) {
    uBarOut[idx] = uBarIn[idx];
    vBarOut[idx] = vBarIn[idx];
    return;
  }
  const bool ex = f & kLinkX, ey = f & kLinkY;
  const bool exLeft = sFlags[ly][lx - 1] & kLinkX, eyUp = sFlags[ly - 1][lx] & kLinkY;
  const float2 tau = __ldg(reinterpret_cast<const float2*>(steps + idx));
  const float tauU = step.tauScale * tau.x;
  const float tauV = step.tauScale * tau.y;

  float divDp = 0.f;
  if (ex) divDp += sDp[ly][lx].x;
  if (exLeft) divDp -= sDp[ly][lx - 1].x;
  if (ey) divDp += sDp[ly][lx].y;
  if (eyUp) divDp -= sDp[ly - 1][lx].y;
  const float uOld = pd.u[idx];
  const float uHat = uOld + tauU * alpha1 * divDp;
  const float uNew = dataProx(uHat, __ldg(&pd.u0[idx]), __ldg(&pd.iu[idx]), __ldg(&pd.iz[idx]), tauU * pd.lambda);
  pd.u[idx] = uNew;
  uBarOut[idx] = uNew + step.theta * (uNew - uOld);

  const float4 q = sQ[ly][lx], qLeft = sQ[ly][lx - 1], qUp = sQ[ly - 1][lx];
  float div0 = 0.f, div1 = 0.f;
  if (ex) div0 += q.x;
  if (exLeft) div0 -= qLeft.x;
  if (ey) div0 += q.y;
  if (eyUp) div0 -= qUp.y;
  if (ex) div1 += q.z;
  if (exLeft) div1 -= qLeft.z;
  if (ey) div1 += q.w;
  if (eyUp) div1 -= qUp.w;
  const float2 p = sP[ly][lx];
  float2* v = reinterpret_cast<float2*>(pd.v);
  const float2 vOld = v[idx];
  float2 vNew;
  vNew.x = vOld.x + tauV * (alpha1 * p.x + alpha0 * div0);
  vNew.y = vOld.y + tauV * (alpha1 * p.y + alpha0 * div1);
  v[idx] = vNew;
  vBarOut[idx] = make_float2(vNew.x + step.theta * (vNew.x - vOld.x), vNew.y + step.theta * (vNew.y - vOld.y));
}

}  // namespace

cudaError_t launchPrimalDualIteration(cudaStream_t s, const PrimalDualDev& pd, StepDev step, int parity) {
  const dim3 block(kTileW, kTileH), grid = grid2d(pd.width, pd.height, block);
  primalDualKernel<<<grid, block, 0, s>>>(pd, step, parity);
  return cudaGetLastError();
}

}  // namespace cs::cudak
