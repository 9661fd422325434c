// The binding's own CUDA kernels (device_kernels.cu), callable from host C++: GPU arrays
// of any layout to the library's packed float gray, and DeviceStereo's finished outputs
// copied into the arrays handed to Python (the valid mask as bytes).
#pragma once
#include <cuda_runtime_api.h>

#include "pixels.hpp"

namespace cs::py {

// dst[y * width + x] = grayAt(src, type, y, x); sets `bit` in *flag if any value is NaN or
// infinite (the host API refuses such images; the caller reports it after the frame).
// src may alias dst when both are packed float gray (each thread reads its pixel first).
cudaError_t launchToGray(const StridedPixels& src, int type, int width, int height, float* dst, unsigned* flag,
                         unsigned bit, cudaStream_t stream);

struct PackArgs {
  long long n = 0;
  // DeviceStereo's outputs (cs::cuda::DeviceDepth), already finished.
  const float *validIn = nullptr, *radial = nullptr, *z = nullptr, *disparity = nullptr, *warp = nullptr,
              *points = nullptr, *confidence = nullptr;
  // Where to copy them; null for outputs not wanted (valid and radial always are).
  unsigned char* valid = nullptr;
  float *outRadial = nullptr, *outZ = nullptr, *outPoints = nullptr, *outDisparity = nullptr, *outWarp = nullptr,
        *outConfidence = nullptr;
};
cudaError_t launchPackResult(const PackArgs& args, cudaStream_t stream);

}  // namespace cs::py
