// fill() and copy(): queued copies and fills of disjoint buffers run as one launch; small
// uploads carried by their launch.
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "common.cuh"

namespace cs::cudak {

namespace {
__global__ void memOpsKernel(MemOps ops) {
  beginKernel();
  const MemOp o = ops.op[blockIdx.y];
  const size_t stride = size_t(gridDim.x) * blockDim.x;
  const size_t first = blockIdx.x * size_t(blockDim.x) + threadIdx.x;
  const bool vector = o.count % 4 == 0 && reinterpret_cast<uintptr_t>(o.dst) % 16 == 0 &&
                      (!o.src || reinterpret_cast<uintptr_t>(o.src) % 16 == 0);
  if (vector) {
    float4* dst = reinterpret_cast<float4*>(o.dst);
    const float4* src = reinterpret_cast<const float4*>(o.src);
    const float4 value = make_float4(o.value, o.value, o.value, o.value);
    for (size_t i = first; i < o.count / 4; i += stride) dst[i] = src ? src[i] : value;
  } else {
    for (size_t i = first; i < o.count; i += stride) o.dst[i] = o.src ? o.src[i] : o.value;
  }
}

__global__ void setFloatsKernel(float* dst, InlineFloats values) {
  beginKernel();
  if (int(threadIdx.x) < values.count) dst[threadIdx.x] = values.value[threadIdx.x];
}

// unitFromByte with an explicitly rounded division, whatever the compiler's flags: the
// host's float v / 255.f, bit for bit.
__device__ float unitFromByteDevice(unsigned v) { return __fdiv_rn(float(v), 255.f); }

// Four bytes a thread, one word read and one float4 written where n allows.
__global__ void floatsFromBytesKernel(float* dst, const uint8_t* src, size_t n) {
  beginKernel();
  const size_t quad = blockIdx.x * size_t(blockDim.x) + threadIdx.x, first = 4 * quad;
  if (first + 4 <= n) {
    const uchar4 b = reinterpret_cast<const uchar4*>(src)[quad];
    reinterpret_cast<float4*>(dst)[quad] =
        make_float4(unitFromByteDevice(b.x), unitFromByteDevice(b.y), unitFromByteDevice(b.z), unitFromByteDevice(b.w));
  } else {
    for (size_t i = first; i < n; ++i) dst[i] = unitFromByteDevice(src[i]);
  }
}
}  // namespace

bool dependentLaunchSupported() {
  // Per device, cached: a frame launches hundreds of kernels. CURVESTEREO_CUDA_PDL=0 turns
  // the dependent launches off (to measure what they bring, or to rule them out).
  static const bool disabled = [] {
    const char* v = std::getenv("CURVESTEREO_CUDA_PDL");
    return v && std::strcmp(v, "0") == 0;
  }();
  static std::atomic<signed char> known[64] = {};
  int device = 0;
  if (disabled || cudaGetDevice(&device) != cudaSuccess || device < 0 || device >= 64) return false;
  signed char k = known[device].load(std::memory_order_relaxed);
  if (k == 0) {
    int major = 0;
    if (cudaDeviceGetAttribute(&major, cudaDevAttrComputeCapabilityMajor, device) != cudaSuccess) return false;
    k = major >= 9 ? 1 : -1;
    known[device].store(k, std::memory_order_relaxed);
  }
  return k > 0;
}

cudaError_t launchMemOps(cudaStream_t s, const MemOps& ops) {
  if (ops.count <= 0) return cudaSuccess;
  size_t largest = 0;
  for (int i = 0; i < ops.count; ++i) largest = std::max(largest, ops.op[i].count);
  const unsigned blocks = unsigned(std::max<size_t>(1, std::min<size_t>((largest / 4 + 255) / 256, 2048)));
  CS_LAUNCH(memOpsKernel, dim3(blocks, unsigned(ops.count)), 256, 0, s, ops);
  return cudaGetLastError();
}

// dst and src are cudaMalloc'd (aligned for the float4 and uchar4 accesses).
cudaError_t launchFloatsFromBytes(cudaStream_t s, float* dst, const uint8_t* src, size_t n) {
  if (n == 0) return cudaSuccess;
  const size_t quads = (n + 3) / 4;
  CS_LAUNCH(floatsFromBytesKernel, unsigned((quads + 255) / 256), 256, 0, s, dst, src, n);
  return cudaGetLastError();
}

cudaError_t launchSetFloats(cudaStream_t s, float* dst, const InlineFloats& values) {
  if (values.count <= 0) return cudaSuccess;
  if (values.count > kMaxInlineFloats) return cudaErrorInvalidValue;
  CS_LAUNCH(setFloatsKernel, 1, kMaxInlineFloats, 0, s, dst, values);
  return cudaGetLastError();
}

}  // namespace cs::cudak
