// The Vulkan side of Backend::normalise: mirrors of the parameter block and push constants
// of shaders/normalise_moments.comp and shaders/normalise.comp, filled from
// NormaliseParams (the dispatch itself is VulkanBackend::normalise).
#pragma once
#include <algorithm>
#include <cstdint>
#include <string>

#include "curvestereo/backend.hpp"
#include "curvestereo/image.hpp"

namespace cs::vk {

// std430 NormaliseParamsRef of shaders/normalise.glsl.
struct NormaliseBlock {
  int32_t radius;
  float epsilon;
  float taps[2 * kMaxNormaliseRadius + 1];
};
static_assert(sizeof(NormaliseBlock) == 8 + 4 * 49, "NormaliseBlock must match shaders/normalise.glsl");

struct PcNormaliseMoments {
  uint64_t moments, src, mask, params;
  int32_t w, h;
};
struct PcNormalise {
  uint64_t dst, moments, src, mask, params;
  int32_t w, h;
};

// The block for p (taps past 2 radius zero, so equal parameters give equal blocks); p.radius
// is in [0, kMaxNormaliseRadius] (Backend::normalise checked it).
inline NormaliseBlock normaliseBlock(const NormaliseParams& p) {
  NormaliseBlock b{};
  b.radius = p.radius;
  b.epsilon = p.epsilon;
  std::copy(p.taps, p.taps + 2 * p.radius + 1, b.taps);
  return b;
}

}  // namespace cs::vk
