// The one place that knows which backends this build contains.
#include <memory>

#include "cpu_backend.hpp"
#include "curvestereo/backend.hpp"
#include "curvestereo/image.hpp"

namespace cs {

std::vector<std::string> availableBackends() { return {"cpu"}; }

std::unique_ptr<Backend> createBackend(const std::string& name, std::string* why) {
  const std::vector<std::string> available = availableBackends();
  if (name == "auto") {
    if (why) *why = "auto: using cpu (no GPU backend is compiled into this build)";
    return std::make_unique<cpu::CpuBackend>();
  }
  if (name == "cpu") {
    if (why) *why = "cpu: requested";
    return std::make_unique<cpu::CpuBackend>();
  }
  std::string list;
  for (auto& n : available) list += (list.empty() ? "" : ", ") + n;
  throw Error("backend '" + name + "' is not available in this build (available: " + list + ", auto)");
}

}  // namespace cs
