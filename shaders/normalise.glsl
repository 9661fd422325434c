// Shared by the two passes of the local contrast normalisation (normalise_moments.comp,
// normalise.comp): the parameter block, read by device address (49 taps do not fit in
// the 128 bytes of push constants).
#ifndef CS_NORMALISE_GLSL
#define CS_NORMALISE_GLSL
#include "common.glsl"

// Mirrors vk::NormaliseBlock in backend_vulkan/normalise.hpp (NormaliseParams).
layout(buffer_reference, std430, buffer_reference_align = 4) buffer NormaliseParamsRef {
  int radius;     // taps[0 .. 2 radius]
  float epsilon;  // contrast floor
  float taps[49];
};

#endif
