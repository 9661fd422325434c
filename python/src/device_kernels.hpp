// The binding's own CUDA kernels (device_kernels.cu), callable from host C++: GPU arrays
// of any layout to the library's packed float gray, and the host API's final pass over
// the result (stereo.cpp finish()) so that device results equal host results bit for bit.
#pragma once
#include <cuda_runtime_api.h>

#include "pixels.hpp"

namespace cs::py {

// dst[y * width + x] = grayAt(src, type, y, x); sets `bit` in *flag if any value is NaN or
// infinite (the host API refuses such images; the caller reports it after the frame).
// src may alias dst when both are packed float gray (each thread reads its pixel first).
cudaError_t launchToGray(const StridedPixels& src, int type, int width, int height, float* dst, unsigned* flag,
                         unsigned bit, cudaStream_t stream);

struct FinishArgs {
  long long n = 0;
  // DeviceStereo's outputs (cs::cuda::DeviceDepth); confidence may be null.
  const float *radial = nullptr, *disparity = nullptr, *warp = nullptr, *points = nullptr, *confidence = nullptr;
  // Which optional outputs were asked for: with none, the valid mask comes from radial
  // alone (finishDepthOnly), else also from finite disparity and warp (finishAll).
  bool withDisparity = true, withWarp = true, withPoints = true;
  // Where to write; null for outputs not wanted.
  unsigned char* valid = nullptr;
  float *outRadial = nullptr, *outZ = nullptr, *outPoints = nullptr, *outDisparity = nullptr, *outWarp = nullptr,
        *outConfidence = nullptr;
};
cudaError_t launchFinish(const FinishArgs& args, cudaStream_t stream);

}  // namespace cs::py
