// Preconditioned primal-dual iterations of anisotropic TGV-L1 (cpu/primal_dual.cpp): two
// or five iterations per launch (primalDualTiledKernel), an odd one left over in a launch
// of its own (primalDualKernel).
// Each iteration fuses the dual and the primal pass: a block computes the new
// duals p, q (and D p) of its tile plus a one-pixel halo to the left and above into
// shared memory, then the primal update of its tile from there. The state ping-pongs
// between two buffer sets (read one, write the other), so a block never reads what a
// neighbouring block of the same launch wrote.

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
  return x >= 0 && y >= 0 && x < w && y < h && __ldg(&mask[y * w + x]) != 0.f;
}

enum : unsigned char { kMasked = 1, kLinkX = 2, kLinkY = 4 };

struct SharedTile {
  float2 p[kDualH][kDualW];
  float2 dp[kDualH][kDualW];
  float4 q[kDualH][kDualW];
  unsigned char flags[kDualH][kDualW];
};

// The dual update of one masked pixel: p, q ascend and are projected onto the unit
// balls; the same expressions, in the same order, as backend_cpu/primal_dual.cpp.
__device__ __forceinline__ void dualPixel(float2& p, float4& q, const float4 t, const float2 sigmaP, bool ex, bool ey,
                                          float ub, float ur, float ud, float2 vb, float2 vr, float2 vd,
                                          const DeviceStep step, float alpha1) {
  float gx = 0.f, gy = 0.f;
  float2 vgx = make_float2(0.f, 0.f), vgy = make_float2(0.f, 0.f);
  if (ex) {
    gx = ur - ub;
    vgx = make_float2(vr.x - vb.x, vr.y - vb.y);
  }
  if (ey) {
    gy = ud - ub;
    vgy = make_float2(vd.x - vb.x, vd.y - vb.y);
  }
  const float a1 = t.x * gx + t.y * gy - vb.x;
  const float a2 = t.y * gx + t.z * gy - vb.y;
  p.x = p.x + step.sigmaScale * sigmaP.x * alpha1 * a1;
  p.y = p.y + step.sigmaScale * sigmaP.y * alpha1 * a2;
  {
    float sum = 0.f;
    sum += p.x * p.x;
    sum += p.y * p.y;
    const float norm = sqrtf(sum);
    if (norm > 1.f) {
      p.x /= norm;
      p.y /= norm;
    }
  }
  q.x = q.x + step.qAscent * vgx.x;
  q.y = q.y + step.qAscent * vgy.x;
  q.z = q.z + step.qAscent * vgx.y;
  q.w = q.w + step.qAscent * vgy.y;
  {
    float sum = 0.f;
    sum += q.x * q.x;
    sum += q.y * q.y;
    sum += q.z * q.z;
    sum += q.w * q.w;
    const float norm = sqrtf(sum);
    if (norm > 1.f) {
      q.x /= norm;
      q.y /= norm;
      q.z /= norm;
      q.w /= norm;
    }
  }
}

// The primal update of the masked pixel at (lx, ly) of the shared tile (its duals and
// those left and above it there). Returns u, v; uBar, vBar through the references.
// The per-pixel constants of the primal update: the step sizes and the linearised data term.
struct PrimalConstants {
  float2 tau;
  float u0, iu, iz;
};

__device__ __forceinline__ PrimalConstants loadPrimalConstants(const PrimalDualDev& pd, int idx) {
  PrimalConstants c;
  c.tau = __ldg(reinterpret_cast<const float2*>(reinterpret_cast<const float4*>(pd.steps) + idx));
  c.u0 = __ldg(&pd.u0[idx]);
  c.iu = __ldg(&pd.iu[idx]);
  c.iz = __ldg(&pd.iz[idx]);
  return c;
}

template <class Tile>
__device__ __forceinline__ void primalPixel(const PrimalDualDev& pd, const Tile& s, int lx, int ly,
                                            const PrimalConstants& c, const DeviceStep step, float uOld, float2 vOld,
                                            float& uNew, float2& vNew, float& uBar, float2& vBar) {
  const float alpha0 = pd.weights.alpha0, alpha1 = pd.weights.alpha1;
  const unsigned char f = s.flags[ly][lx];
  const bool ex = f & kLinkX, ey = f & kLinkY;
  const bool exLeft = s.flags[ly][lx - 1] & kLinkX, eyUp = s.flags[ly - 1][lx] & kLinkY;
  const float tauU = step.tauScale * c.tau.x;
  const float tauV = step.tauScale * c.tau.y;
  float divDp = 0.f;
  if (ex) divDp += s.dp[ly][lx].x;
  if (exLeft) divDp -= s.dp[ly][lx - 1].x;
  if (ey) divDp += s.dp[ly][lx].y;
  if (eyUp) divDp -= s.dp[ly - 1][lx].y;
  const float uHat = uOld + tauU * alpha1 * divDp;
  uNew = dataProx(uHat, c.u0, c.iu, c.iz, tauU * pd.weights.lambda);
  uBar = uNew + step.theta * (uNew - uOld);
  const float4 q = s.q[ly][lx], qLeft = s.q[ly][lx - 1], qUp = s.q[ly - 1][lx];
  float div0 = 0.f, div1 = 0.f;
  if (ex) div0 += q.x;
  if (exLeft) div0 -= qLeft.x;
  if (ey) div0 += q.y;
  if (eyUp) div0 -= qUp.y;
  if (ex) div1 += q.z;
  if (exLeft) div1 -= qLeft.z;
  if (ey) div1 += q.w;
  if (eyUp) div1 -= qUp.w;
  const float2 p = s.p[ly][lx];
  vNew.x = vOld.x + tauV * (alpha1 * p.x + alpha0 * div0);
  vNew.y = vOld.y + tauV * (alpha1 * p.y + alpha0 * div1);
  vBar = make_float2(vNew.x + step.theta * (vNew.x - vOld.x), vNew.y + step.theta * (vNew.y - vOld.y));
}

// One iteration over the block's tile (the dual pass over the tile and its halo into
// shared memory, a barrier, the primal pass). Pixels outside the mask keep their values
// (copied from the read set to the written one).
__device__ __forceinline__ void iterateTile(const PrimalDualDev& pd, const DeviceStep step, int parity, SharedTile& s) {
  const int w = pd.width, h = pd.height;
  const int x0 = blockIdx.x * kTileW, y0 = blockIdx.y * kTileH;
  const int tid = threadIdx.y * kTileW + threadIdx.x;
  const float* uBarIn = pd.uBar[parity];
  const float2* vBarIn = reinterpret_cast<const float2*>(pd.vBar[parity]);
  const float2* pIn = reinterpret_cast<const float2*>(pd.p[parity]);
  const float4* qIn = reinterpret_cast<const float4*>(pd.q[parity]);
  float2* pOut = reinterpret_cast<float2*>(pd.p[1 - parity]);
  float4* qOut = reinterpret_cast<float4*>(pd.q[1 - parity]);
  const float4* __restrict__ tensor = reinterpret_cast<const float4*>(pd.tensor);
  const float4* __restrict__ steps = reinterpret_cast<const float4*>(pd.steps);
  const float alpha1 = pd.weights.alpha1;
  // u and v go from set `parity` to the other one, so that this kernel can alternate with
  // the tiled kernel.
  float* uIn = pd.u[parity];
  float* uOutP = pd.u[1 - parity];
  float2* vIn = reinterpret_cast<float2*>(pd.v[parity]);
  float2* vOutP = reinterpret_cast<float2*>(pd.v[1 - parity]);

  // --- dual pass over the tile and its halo ---
  for (int k = tid; k < kDualW * kDualH; k += kTileW * kTileH) {
    const int lx = k % kDualW, ly = k / kDualW;
    const int i = x0 - 1 + lx, j = y0 - 1 + ly;
    float2 p = make_float2(0.f, 0.f);
    float4 q = make_float4(0.f, 0.f, 0.f, 0.f);
    float4 t = make_float4(0.f, 0.f, 0.f, 0.f);
    unsigned char flags = 0;
    if (i >= 0 && j >= 0 && i < w && j < h) {
      const int idx = j * w + i;  // 32-bit: fewer registers (a level has < 2^31 pixels)
      p = __ldg(&pIn[idx]);
      q = __ldg(&qIn[idx]);
      const float m = __ldg(&pd.mask[idx]);
      bool ex = false, ey = false;
      float2 sigmaP = make_float2(0.f, 0.f), vb = make_float2(0.f, 0.f), vr = vb, vd = vb;
      float ub = 0.f, ur = 0.f, ud = 0.f;
      if (m != 0.f) {
        ex = isMasked(pd.mask, w, h, i + 1, j);
        ey = isMasked(pd.mask, w, h, i, j + 1);
        t = __ldg(&tensor[idx]);
        sigmaP = __ldg(reinterpret_cast<const float2*>(steps + idx) + 1);
        ub = __ldg(&uBarIn[idx]);
        vb = __ldg(&vBarIn[idx]);
        if (ex) {
          ur = __ldg(&uBarIn[idx + 1]);
          vr = __ldg(&vBarIn[idx + 1]);
        }
        if (ey) {
          ud = __ldg(&uBarIn[idx + w]);
          vd = __ldg(&vBarIn[idx + w]);
        }
        flags = kMasked | (ex ? kLinkX : 0) | (ey ? kLinkY : 0);
        dualPixel(p, q, t, sigmaP, ex, ey, ub, ur, ud, vb, vr, vd, step, alpha1);
      }
      if (lx > 0 && ly > 0) {  // the tile's own pixels: write the new (or unchanged) duals
        pOut[idx] = p;
        qOut[idx] = q;
      }
    }
    s.p[ly][lx] = p;
    s.q[ly][lx] = q;
    s.dp[ly][lx] = make_float2(t.x * p.x + t.y * p.y, t.y * p.x + t.z * p.y);
    s.flags[ly][lx] = flags;
  }
  __syncthreads();

  // --- primal pass over the tile ---
  const int x = x0 + threadIdx.x, y = y0 + threadIdx.y;
  const int lx = threadIdx.x + 1, ly = threadIdx.y + 1;
  if (x >= w || y >= h) return;
  const int idx = y * w + x;
  float* uBarOut = pd.uBar[1 - parity];
  float2* vBarOut = reinterpret_cast<float2*>(pd.vBar[1 - parity]);
  const unsigned char f = s.flags[ly][lx];
  if (!(f & kMasked)) {
    uBarOut[idx] = __ldg(&uBarIn[idx]);
    vBarOut[idx] = __ldg(&vBarIn[idx]);
    uOutP[idx] = uIn[idx];
    vOutP[idx] = vIn[idx];
    return;
  }
  // u and v: read and written by this thread alone, at its own pixel.
  const float uOld = uIn[idx];
  const float2 vOld = vIn[idx];
  float uNew, uBar;
  float2 vNew, vBar;
  primalPixel(pd, s, lx, ly, loadPrimalConstants(pd, idx), step, uOld, vOld, uNew, vNew, uBar, vBar);
  uOutP[idx] = uNew;
  uBarOut[idx] = uBar;
  vOutP[idx] = vNew;
  vBarOut[idx] = vBar;
}

// One iteration per launch (levels with more tiles than the device holds at once).
__global__ void __launch_bounds__(kTileW* kTileH, kMinBlocks)
    primalDualKernel(PrimalDualDev pd, DeviceStep step, int parity) {
  beginKernel();
  __shared__ SharedTile s;
  iterateTile(pd, step, parity, s);
}

// Several iterations per launch (temporal blocking), one cell per thread: a block of
// 32x16 threads covers its tile plus the halo the iterations need, and each thread owns one
// cell for the whole launch. A thread issues every global load of the first iteration at
// its start, so that the block waits for memory once (the kernel is bound by latency as
// much as by bandwidth: this replaced a 32x16 tile whose halo cells took second rounds of
// loads in three of the four phases of a two-iteration launch, 43 -> 35 us per launch at
// 848x800 under ncu on an H200). The phases exchange neighbours' values through shared
// memory, each on one cell less than the last. Every per-pixel expression is the one of
// iterateTile, in the same order. Large levels take two iterations per launch (a 29x13
// tile: the halo's redundant work grows with the iterations, and memory traffic matters
// there); levels whose five-iteration tiles (23x7) all fit on the device at once take
// five, since there the launches' latency is what costs (H200, T265 frame, N=20: levels
// 212x200 and 106x100, 6.39 -> 6.35 ms a frame; 53x50 since the cluster kernel went).
constexpr int kCellsW = 32, kCellsH = 16;  // threads = cells
constexpr int kDeepIterations = 5;
// 3 blocks of 512 threads on sm_80 / sm_86+ (40 registers), 2 on Turing's 1024 threads.
// Later iterations reload their constants (L1 hits) rather than holding them in
// registers from the first: holding them spills at 40 registers and measured slower.
constexpr int kMinBlocksTiled = kMinBlocks >= 6 ? 3 : 2;

struct CellTile {
  float2 p[kCellsH][kCellsW];
  float2 dp[kCellsH][kCellsW];
  float4 q[kCellsH][kCellsW];
  float uBar[kCellsH][kCellsW];
  float2 vBar[kCellsH][kCellsW];
  unsigned char flags[kCellsH][kCellsW];
};

// Pixels outside the mask never change, and no masked pixel reads them, so only the first
// launch of a call copies them into the other set (`home`: also set 0's uBar, vBar where
// that launch read uBarFirst, vBarFirst instead); later launches neither read nor write
// them: the two sets already agree there. (A fisheye frame's corners are a fifth of it.)
struct MaskedOutCopy {
  bool copy;  // the first launch of the call
  float* uBarHome;
  float* vBarHome;  // null: set 0's uBar, vBar were what the launch read
};

// kIters iterations in one launch: a block of 32x16 cells writes a (33 - 2 kIters) x
// (17 - 2 kIters) tile; iteration `it`'s dual pass runs on the cells [it, 31 - it] and its
// primal pass on [it + 1, 31 - it] (each needs one more neighbour than the last left), so
// the written tile is [kIters, 32 - kIters] (pixel (0, 0) of the tile at cell kIters).
template <int kIters>
struct StepBatch {
  DeviceStep step[kIters];
};

enum : int { kNothingSettled, kGeometrySettled, kAllSettled };

template <int kIters>
__global__ void __launch_bounds__(kCellsW* kCellsH, kMinBlocksTiled)
    primalDualTiledKernel(PrimalDualDev pd, StepBatch<kIters> steps, int parity, MaskedOutCopy outside, int settled) {
  // What the previous kernel cannot have written (kGeometrySettled: mask, tensor, steps;
  // kAllSettled: the data term too) is loaded while it finishes (programmatic dependent
  // launch); the rest after waiting for it.
  if (settled == kNothingSettled) awaitPreviousKernel();
  __shared__ CellTile s;
  constexpr int kTileW = kCellsW + 1 - 2 * kIters, kTileH = kCellsH + 1 - 2 * kIters;
  const int w = pd.width, h = pd.height;
  const int lx = threadIdx.x, ly = threadIdx.y;
  const int i = blockIdx.x * kTileW - kIters + lx, j = blockIdx.y * kTileH - kIters + ly;
  const bool inImage = i >= 0 && j >= 0 && i < w && j < h;
  const int idx = inImage ? j * w + i : 0;
  const float alpha1 = pd.weights.alpha1;
  const bool right = i + 1 < w, down = j + 1 < h;
  const float m = inImage ? __ldg(&pd.mask[idx]) : 0.f;
  const bool live = inImage && (m != 0.f || outside.copy);

  // --- every load, then the first iteration's dual pass (all cells) ---
  float2 p = make_float2(0.f, 0.f), sigmaP = p, vOld = p, vBar = p;
  float4 q = make_float4(0.f, 0.f, 0.f, 0.f), t = q;
  float uOld = 0.f, uBar = 0.f;
  PrimalConstants c{};
  unsigned char flags = 0;
  float mRight = 0.f, mDown = 0.f;
  float4 tensorHere = t, st = t;
  if (live) {
    mRight = right ? __ldg(&pd.mask[idx + 1]) : 0.f;
    mDown = down ? __ldg(&pd.mask[idx + w]) : 0.f;
    tensorHere = __ldg(reinterpret_cast<const float4*>(pd.tensor) + idx);
    st = __ldg(reinterpret_cast<const float4*>(pd.steps) + idx);
  }
  if (settled == kGeometrySettled) awaitPreviousKernel();
  if (live) {
    c.u0 = __ldg(&pd.u0[idx]);
    c.iu = __ldg(&pd.iu[idx]);
    c.iz = __ldg(&pd.iz[idx]);
  }
  if (settled == kAllSettled) awaitPreviousKernel();
  releaseNextKernel();
  if (live) {
    const float* uBarIn = pd.uBar[parity];
    const float2* vBarIn = reinterpret_cast<const float2*>(pd.vBar[parity]);
    p = __ldg(reinterpret_cast<const float2*>(pd.p[parity]) + idx);
    q = __ldg(reinterpret_cast<const float4*>(pd.q[parity]) + idx);
    uBar = __ldg(&uBarIn[idx]);
    vBar = __ldg(&vBarIn[idx]);
    const float ur = right ? __ldg(&uBarIn[idx + 1]) : 0.f;
    const float2 vr = right ? __ldg(&vBarIn[idx + 1]) : make_float2(0.f, 0.f);
    const float ud = down ? __ldg(&uBarIn[idx + w]) : 0.f;
    const float2 vd = down ? __ldg(&vBarIn[idx + w]) : make_float2(0.f, 0.f);
    uOld = __ldg(&pd.u[parity][idx]);
    vOld = __ldg(reinterpret_cast<const float2*>(pd.v[parity]) + idx);
    c.tau = make_float2(st.x, st.y);
    sigmaP = make_float2(st.z, st.w);
    if (m != 0.f) {
      const bool ex = mRight != 0.f, ey = mDown != 0.f;
      t = tensorHere;
      flags = kMasked | (ex ? kLinkX : 0) | (ey ? kLinkY : 0);
      dualPixel(p, q, t, sigmaP, ex, ey, uBar, ur, ud, vBar, vr, vd, steps.step[0], alpha1);
    }
  }
  s.p[ly][lx] = p;
  s.q[ly][lx] = q;
  s.dp[ly][lx] = make_float2(t.x * p.x + t.y * p.y, t.y * p.x + t.z * p.y);
  s.flags[ly][lx] = flags;
  __syncthreads();

  // --- first iteration, primal pass: all but the left column and the top row ---
  const bool masked = flags & kMasked;
  float u = uOld;
  float2 v = vOld;
  if (masked && lx >= 1 && ly >= 1) primalPixel(pd, s, lx, ly, c, steps.step[0], uOld, vOld, u, v, uBar, vBar);
  s.uBar[ly][lx] = uBar;
  s.vBar[ly][lx] = vBar;
  __syncthreads();

  // Iterations 1 .. kIters - 1: the dual pass on [it, 31 - it] (in place), then the
  // primal pass on [it + 1, 31 - it]; the last one's primal pass on the written tile only.
#pragma unroll
  for (int it = 1; it < kIters; ++it) {
    const bool dualCell = inImage && lx >= it && ly >= it && lx < kCellsW - it && ly < kCellsH - it;
    if (dualCell && masked) {
      const bool ex = flags & kLinkX, ey = flags & kLinkY;
      t = __ldg(reinterpret_cast<const float4*>(pd.tensor) + idx);  // L1 hits
      sigmaP = __ldg(reinterpret_cast<const float2*>(reinterpret_cast<const float4*>(pd.steps) + idx) + 1);
      float ur = 0.f, ud = 0.f;
      float2 vr = make_float2(0.f, 0.f), vd = vr;
      if (ex) {
        ur = s.uBar[ly][lx + 1];
        vr = s.vBar[ly][lx + 1];
      }
      if (ey) {
        ud = s.uBar[ly + 1][lx];
        vd = s.vBar[ly + 1][lx];
      }
      dualPixel(p, q, t, sigmaP, ex, ey, uBar, ur, ud, vBar, vr, vd, steps.step[it], alpha1);
      s.p[ly][lx] = p;
      s.q[ly][lx] = q;
      s.dp[ly][lx] = make_float2(t.x * p.x + t.y * p.y, t.y * p.x + t.z * p.y);
    }
    const bool last = it + 1 == kIters;
    // The written tile: [kIters, 32 - kIters].
    const bool own = last && live && lx >= kIters && ly >= kIters && lx <= kCellsW - kIters && ly <= kCellsH - kIters;
    if (own) {
      reinterpret_cast<float2*>(pd.p[1 - parity])[idx] = p;
      reinterpret_cast<float4*>(pd.q[1 - parity])[idx] = q;
    }
    __syncthreads();
    if (last) {
      if (!own) return;
      float uNew = u, uBarNew = uBar;
      float2 vNew = v, vBarNew = vBar;
      if (masked)
        primalPixel(pd, s, lx, ly, loadPrimalConstants(pd, idx), steps.step[it], u, v, uNew, vNew, uBarNew, vBarNew);
      u = uNew, v = vNew, uBar = uBarNew, vBar = vBarNew;
    } else {
      if (dualCell && lx > it && ly > it && masked)
        primalPixel(pd, s, lx, ly, loadPrimalConstants(pd, idx), steps.step[it], u, v, u, v, uBar, vBar);
      s.uBar[ly][lx] = uBar;
      s.vBar[ly][lx] = vBar;
      __syncthreads();
    }
  }

  if (!masked && outside.uBarHome) {
    outside.uBarHome[idx] = uBar;
    reinterpret_cast<float2*>(outside.vBarHome)[idx] = vBar;
  }
  pd.u[1 - parity][idx] = u;
  reinterpret_cast<float2*>(pd.v[1 - parity])[idx] = v;
  pd.uBar[1 - parity][idx] = uBar;
  reinterpret_cast<float2*>(pd.vBar[1 - parity])[idx] = vBar;
}

}  // namespace

int primalDualTiledResidentBlocks(int device) {
  int sms = 0, perSm = 0;
  if (cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, device) != cudaSuccess ||
      cudaOccupancyMaxActiveBlocksPerMultiprocessor(&perSm, primalDualTiledKernel<kDeepIterations>, kCellsW * kCellsH,
                                                    0) != cudaSuccess) {
    cudaGetLastError();
    return 0;
  }
  return sms * perSm;
}

// The grid of primalDualTiledKernel<iterations> over the level.
static dim3 tiledGrid(const PrimalDualDev& pd, int iterations) {
  const int tileW = kCellsW + 1 - 2 * iterations, tileH = kCellsH + 1 - 2 * iterations;
  return dim3((pd.width + tileW - 1) / tileW, (pd.height + tileH - 1) / tileH);
}

// One launch of primalDualTiledKernel<kIters>: steps[0 .. kIters) from set `parity`.
template <int kIters>
static cudaError_t launchTiled(cudaStream_t s, const PrimalDualDev& pd, const DeviceStep* steps, int parity,
                               MaskedOutCopy outside, int settled) {
  StepBatch<kIters> batch{};
  for (int i = 0; i < kIters; ++i) batch.step[i] = steps[i];
  CS_LAUNCH(primalDualTiledKernel<kIters>, tiledGrid(pd, kIters), dim3(kCellsW, kCellsH), 0, s, pd, batch, parity,
            outside, settled);
  return cudaSuccess;
}

cudaError_t launchPrimalDual(cudaStream_t s, const PrimalDualDev& pd, const DeviceStep* steps, int count,
                             int residentTiledBlocks, bool geometrySettled, int& endSet) {
  endSet = 0;
  const dim3 block(kTileW, kTileH), grid = grid2d(pd.width, pd.height, block);
  // Two iterations per launch, the odd one last; every launch goes from one set to the
  // other. The first launch reads set 0 and writes set 1 only, so its uBar, vBar can be
  // read from uBarFirst, vBarFirst in place of set 0's.
  PrimalDualDev first = pd;
  first.uBar[0] = const_cast<float*>(pd.uBarFirst);
  first.vBar[0] = const_cast<float*>(pd.vBarFirst);
  const bool barsElsewhere = pd.uBarFirst != pd.uBar[0];
  const MaskedOutCopy copyOutside{true, barsElsewhere ? pd.uBar[0] : nullptr, barsElsewhere ? pd.vBar[0] : nullptr};
  const MaskedOutCopy leaveOutside{false, nullptr, nullptr};
  const dim3 deepGrid = tiledGrid(pd, kDeepIterations);
  const bool deep = int(deepGrid.x * deepGrid.y) <= residentTiledBlocks;
  int k = 0;
  while (k + 1 < count) {
    const int iterations = deep && count - k >= kDeepIterations ? kDeepIterations : 2;
    const MaskedOutCopy outside = k == 0 ? copyOutside : leaveOutside;
    const int settled = k > 0 ? kAllSettled : geometrySettled ? kGeometrySettled : kNothingSettled;
    const PrimalDualDev& state = k == 0 ? first : pd;
    const cudaError_t e = iterations == kDeepIterations
                              ? launchTiled<kDeepIterations>(s, state, steps + k, endSet, outside, settled)
                              : launchTiled<2>(s, state, steps + k, endSet, outside, settled);
    if (e != cudaSuccess) return e;
    k += iterations;
    endSet ^= 1;
  }
  if (k < count) {
    CS_LAUNCH(primalDualKernel, grid, block, 0, s, k == 0 ? first : pd, steps[k], endSet);
    endSet ^= 1;
  }
  return cudaSuccess;
}

}  // namespace cs::cudak
