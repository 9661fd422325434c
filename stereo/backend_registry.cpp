// The one place that knows which backends this build contains. Each GPU backend, when
// compiled in (CS_HAVE_CUDA / CS_HAVE_VULKAN), provides
//   std::string probe<Name>(const std::string& device);  // "" if usable, else why not
//   std::unique_ptr<Backend> create<Name>Backend(const std::string& device);
// A backend name may carry a device selector after a colon: "vulkan:1", "vulkan:NVIDIA".
#include <memory>

#include "cpu_backend.hpp"
#include "curvestereo/backend.hpp"
#include "curvestereo/backends.hpp"
#include "curvestereo/image.hpp"

#ifdef CS_HAVE_CUDA
#include "cuda_backend.hpp"
#endif
#ifdef CS_HAVE_VULKAN
#include "vulkan_backend.hpp"
#endif

namespace cs {

namespace {

struct Entry {
  std::string name;
  std::string (*probe)(const std::string& device);
  std::unique_ptr<Backend> (*create)(const std::string& device);
  // Optional stricter probe for "auto" (Vulkan: a real GPU only, not lavapipe).
  std::string (*probeAuto)(const std::string& device) = nullptr;
};

std::string probeCpu(const std::string&) { return ""; }
std::unique_ptr<Backend> createCpu(const std::string&) { return std::make_unique<cpu::CpuBackend>(); }

// In order of preference for "auto".
std::vector<Entry> entries() {
  std::vector<Entry> e;
#ifdef CS_HAVE_CUDA
  e.push_back({"cuda", probeCuda, createCudaBackend});
#endif
#ifdef CS_HAVE_VULKAN
  e.push_back({"vulkan", probeVulkan, createVulkanBackend, probeVulkanAuto});
#endif
  e.push_back({"cpu", probeCpu, createCpu});
  return e;
}

}  // namespace

std::vector<std::string> availableBackends() {
  std::vector<std::string> names;
  for (const Entry& e : entries()) names.push_back(e.name);
  return names;
}

std::unique_ptr<Backend> createBackend(const std::string& spec, std::string* why) {
  const auto colon = spec.find(':');
  const std::string name = spec.substr(0, colon), device = colon == std::string::npos ? "" : spec.substr(colon + 1);
  std::string skipped;
  for (const Entry& e : entries()) {
    if (name != "auto" && name != e.name) continue;
    const std::string reason = name == "auto" && e.probeAuto ? e.probeAuto(device) : e.probe(device);
    if (reason.empty()) {
      std::unique_ptr<Backend> b = e.create(device);
      if (why)
        *why = name == "auto" ? "auto: using " + e.name + (skipped.empty() ? "" : " (" + skipped + ")")
                              : e.name + ": requested";
      return b;
    }
    if (name != "auto") throw Error("backend '" + spec + "' is not usable: " + reason);
    skipped += (skipped.empty() ? "" : "; ") + e.name + " skipped: " + reason;
  }
  std::string list;
  for (auto& n : availableBackends()) list += (list.empty() ? "" : ", ") + n;
  throw Error("backend '" + name + "' is not available in this build (available: " + list + ", auto)");
}

// Opening the backend is the only complete test (a Vulkan device may be listed and still fail
// to create its queues), so the probe is a construction.
bool backendAvailable(const std::string& name, std::string* why) {
  try {
    createBackend(name);
    return true;
  } catch (const Error& e) {
    if (why) *why = e.what();
    return false;
  }
}

}  // namespace cs
