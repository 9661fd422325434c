// The SPIR-V modules compiled from ../shaders at build time (generated shader_table.cpp).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace cs::vk {

struct EmbeddedShader {
  const char* name;
  const uint32_t* code;
  size_t bytes;
};

const std::vector<EmbeddedShader>& embeddedShaders();

}  // namespace cs::vk
