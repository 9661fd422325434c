// libFuzzer target: cs::readExr on arbitrary bytes. It must return an image or throw a
// one-line cs::Error; anything else is a finding.
#include <cstdint>
#include <string>

#include "curvestereo/image_io.hpp"
#include "fuzz_util.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& path = cs::fuzz::writeScratch(data, size, ".exr");
  try {
    const auto image = cs::readExr(path);
    if (image.size() != size_t(image.width) * size_t(image.height)) __builtin_trap();
  } catch (const cs::Error& e) {
    if (std::string(e.what()).find('\n') != std::string::npos) __builtin_trap();  // messages are one line
  }
  return 0;
}
