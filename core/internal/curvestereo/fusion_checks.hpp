// The checks a rig's fusion makes of its inputs, shared by the host fusion
// (core/src/rig_fusion.cpp) and the panorama on a backend (stereo/panorama_fusion.cpp).
// Internal: not installed.
#pragma once
#include "curvestereo/camera.hpp"
#include "curvestereo/depth_result.hpp"
#include "curvestereo/image.hpp"

namespace cs {

template <class T>
bool sameSize(const Image<T>& image, const Camera& cam) {
  return image.width == cam.width && image.height == cam.height;
}

// The fusion reads a result's valid mask, radial depth and confidence (and, with
// allOutputs, every other output), so each must be the camera's size: else cs::Error,
// "<what>: a result for a camera of WxH px needs ... at that size".
void checkFusionInput(const DepthResult& r, const Camera& cam, bool allOutputs, const char* what);

}  // namespace cs
