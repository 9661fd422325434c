// Device helpers shared by the kernels: buffer access, the oracle's bilinear sampling
// (explicit arithmetic, clamped to the edge) and the masked-grid links.
#pragma once
#include <cuda_runtime.h>

#include "kernels.hpp"

namespace cs::cudak {

__device__ __forceinline__ float& at(const Img& v, int x, int y, int c = 0) {
  return v.data[(size_t(y) * v.width + x) * v.channels + c];
}
__device__ __forceinline__ bool inside(const Img& v, int x, int y) {
  return x >= 0 && y >= 0 && x < v.width && y < v.height;
}
__device__ __forceinline__ bool masked(const Img& m, int x, int y) { return inside(m, x, y) && at(m, x, y) != 0.f; }
__device__ __forceinline__ bool linkX(const Img& m, int x, int y) { return masked(m, x, y) && masked(m, x + 1, y); }
__device__ __forceinline__ bool linkY(const Img& m, int x, int y) { return masked(m, x, y) && masked(m, x, y + 1); }

// Same arithmetic, in the same order, as cs::cpu::sampleBilinear. Offsets in 32 bits (an
// image has fewer than 2^31 values): the index arithmetic is most of a sample's work.
__device__ __forceinline__ float sampleBilinear(const Img& v, float x, float y, int c = 0) {
  x = fminf(fmaxf(x, 0.f), float(v.width - 1));
  y = fminf(fmaxf(y, 0.f), float(v.height - 1));
  const int x0 = int(floorf(x)), y0 = int(floorf(y));
  const int right = x0 + 1 < v.width ? v.channels : 0;            // to x1 = min(x0 + 1, w - 1)
  const int down = y0 + 1 < v.height ? v.width * v.channels : 0;  // to y1 = min(y0 + 1, h - 1)
  const float fx = x - float(x0), fy = y - float(y0);
  const float* p = v.data + (y0 * v.width + x0) * v.channels + c;
  const float top = __ldg(p) * (1.f - fx) + __ldg(p + right) * fx;
  const float bottom = __ldg(p + down) * (1.f - fx) + __ldg(p + down + right) * fx;
  return top * (1.f - fy) + bottom * fy;
}

// A pixel's inputs of accumulate (cpu/accumulate.cpp), which a kernel may load before the
// estimate is known.
struct AccumulateInputs {
  float u0, wx, wy, tx, ty;
};
__device__ __forceinline__ AccumulateInputs loadAccumulateInputs(const Img& w, const Img& u0, const Img& tangent, int x,
                                                                 int y) {
  return {at(u0, x, y), at(w, x, y, 0), at(w, x, y, 1), at(tangent, x, y, 0), at(tangent, x, y, 1)};
}

// accumulate at one masked pixel from the estimate `uIn`: du = clamp(uIn - u0, +-duMax);
// u = u0 + du; w += du * tangent. Returns the new u; the new w through wx, wy.
__device__ __forceinline__ float accumulateFrom(const AccumulateInputs& in, const Img& u, const Img& w, int x, int y,
                                                float uIn, float duMax, float& wx, float& wy) {
  const float du = fminf(fmaxf(uIn - in.u0, -duMax), duMax);
  const float uNew = in.u0 + du;
  at(u, x, y) = uNew;
  wx = in.wx + du * in.tx;
  wy = in.wy + du * in.ty;
  at(w, x, y, 0) = wx;
  at(w, x, y, 1) = wy;
  return uNew;
}

__device__ __forceinline__ float accumulatePixel(const Img& u, const Img& w, const Img& u0, const Img& tangent, int x,
                                                 int y, float uIn, float duMax, float& wx, float& wy) {
  return accumulateFrom(loadAccumulateInputs(w, u0, tangent, x, y), u, w, x, y, uIn, duMax, wx, wy);
}

inline dim3 grid2d(int w, int h, dim3 block) { return dim3((w + block.x - 1) / block.x, (h + block.y - 1) / block.y); }

// Programmatic dependent launch (sm_90 and newer). A frame is hundreds of short dependent
// kernels; launched with launch() below, a kernel's blocks are scheduled while the previous
// kernel's last blocks still run, instead of after it, which hides the launch latency
// between them. Every kernel therefore calls awaitPreviousKernel() before it touches what
// the previous kernel may have written (its writes are visible after it). Kernels whose
// launcher knows the previous kernel (primal-dual launches after one of their own call or
// after the warp's data term; the warp end after a primal-dual launch) load the buffers it
// cannot have written first; every other kernel waits at its start. All kernels before
// the previous one have finished by then: each waits before it releases the next.
// Both instructions are no-ops when the kernel was launched without the attribute.
__device__ __forceinline__ void awaitPreviousKernel() {
#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ >= 900
  asm volatile("griddepcontrol.wait;" ::: "memory");
#endif
}
// Lets the next kernel's blocks be scheduled once every block of this one has called it
// (or exited). Kernels call it right after awaitPreviousKernel() unless they hold the SMs
// for long (the persistent primal-dual kernel calls it at its end).
__device__ __forceinline__ void releaseNextKernel() {
#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ >= 900
  asm volatile("griddepcontrol.launch_dependents;");
#endif
}
__device__ __forceinline__ void beginKernel() {
  awaitPreviousKernel();
  releaseNextKernel();
}

// Whether the current device takes programmatic dependent launches (compute capability 9+).
bool dependentLaunchSupported();

// kernel<<<grid, block, sharedBytes, s>>>(args...), as a programmatic dependent launch
// where the device supports it.
template <class... Params, class... Args>
cudaError_t launch(void (*kernel)(Params...), dim3 grid, dim3 block, size_t sharedBytes, cudaStream_t s, Args... args) {
  cudaLaunchConfig_t config{};
  config.gridDim = grid;
  config.blockDim = block;
  config.dynamicSmemBytes = sharedBytes;
  config.stream = s;
  cudaLaunchAttribute attribute{};
  attribute.id = cudaLaunchAttributeProgrammaticStreamSerialization;
  attribute.val.programmaticStreamSerializationAllowed = 1;
  config.attrs = &attribute;
  config.numAttrs = dependentLaunchSupported() ? 1 : 0;
  const cudaError_t e = cudaLaunchKernelEx(&config, kernel, Params(args)...);
  return e != cudaSuccess ? e : cudaGetLastError();
}

// launch(...), returning its error from the enclosing launcher if it fails.
#define CS_LAUNCH(...)                                                 \
  do {                                                                 \
    const cudaError_t launchError_ = ::cs::cudak::launch(__VA_ARGS__); \
    if (launchError_ != cudaSuccess) return launchError_;              \
  } while (0)

}  // namespace cs::cudak
