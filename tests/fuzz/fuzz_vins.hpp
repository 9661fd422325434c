// The fuzz_vins input: a VINS-Fusion config, a line "###", and the camodocal camera file
// that every camera file name the config gives reads as (one input, both readers).
#pragma once
#include <string>

#include "curvestereo/rig.hpp"

namespace cs::fuzz {

inline Rig parseVinsInput(const std::string& text) {
  const size_t split = text.find("\n###\n");
  const std::string config = text.substr(0, split);
  const std::string camera = split == std::string::npos ? std::string() : text.substr(split + 5);
  return parseVinsFusion(config, "fuzz.yaml", [&](const std::string&) { return camera; });
}

}  // namespace cs::fuzz
