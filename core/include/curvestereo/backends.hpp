// Which backends this build has and whether one can run here, for choosing the `backend`
// argument of cs::Stereo (stereo.hpp includes this) without constructing a Stereo.
#pragma once
#include <string>
#include <vector>

namespace cs {

// Backends compiled into this build, in order of preference for "auto".
std::vector<std::string> availableBackends();

// Whether `name` ("cpu", "cuda", "vulkan" or "auto", with an optional device after a colon,
// "vulkan:1") can run here: compiled in, and its device found and opened (the device is
// closed again at once). If not, *why (optional) receives the reason, one line.
bool backendAvailable(const std::string& name, std::string* why = nullptr);

}  // namespace cs
