// The Vulkan device layer (device.hpp): loader, instance, validation messages, device
// selection.
#include "device.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>

#include "curvestereo/image.hpp"
#include "vulkan_backend.hpp"

namespace cs {
namespace vk {

namespace {

// Validation messages.
std::atomic<long long> gValidationCount{0};
std::atomic<bool> gLayerActive{false};
std::mutex gValidationMutex;
std::string gLastValidationMessage;

VKAPI_ATTR VkBool32 VKAPI_CALL debugCallback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                             VkDebugUtilsMessageTypeFlagsEXT,
                                             const VkDebugUtilsMessengerCallbackDataEXT* data, void*) {
  if (severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
    ++gValidationCount;
    const char* msg = data && data->pMessage ? data->pMessage : "(no message)";
    {
      std::lock_guard<std::mutex> lock(gValidationMutex);
      gLastValidationMessage = msg;
    }
    std::fprintf(stderr, "[vulkan validation] %s\n", msg);
  }
  return VK_FALSE;
}

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

int typeRank(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
      return 0;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
      return 1;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
      return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU:
      return 3;
    default:
      return 4;
  }
}

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

// The process-wide loader, opened once.
const Loader& loader() {
  static const Loader instance = [] {
    Loader l;
    for (const char* name : {"libvulkan.so.1", "libvulkan.so"}) {
      l.lib = dlopen(name, RTLD_NOW | RTLD_LOCAL);
      if (l.lib) break;
    }
    if (!l.lib) {
      l.error = "no Vulkan loader (libvulkan.so.1 not found)";
      return l;
    }
    l.getInstanceProcAddr = reinterpret_cast<PFN_vkGetInstanceProcAddr>(dlsym(l.lib, "vkGetInstanceProcAddr"));
    if (!l.getInstanceProcAddr) {
      l.error = "no Vulkan loader (libvulkan has no vkGetInstanceProcAddr)";
      return l;
    }
#define CS_VK_LOAD_GLOBAL(name) l.name = reinterpret_cast<PFN_##name>(l.getInstanceProcAddr(nullptr, #name));
    CS_VK_GLOBAL_FNS(CS_VK_LOAD_GLOBAL)
#undef CS_VK_LOAD_GLOBAL
    if (!l.vkCreateInstance) l.error = "no Vulkan loader (vkCreateInstance missing)";
    return l;
  }();
  return instance;
}

std::string resultText(VkResult r) {
  switch (r) {
    case VK_SUCCESS:
      return "success";
    case VK_TIMEOUT:
      return "timeout";
    case VK_ERROR_OUT_OF_HOST_MEMORY:
      return "out of host memory";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY:
      return "out of device memory";
    case VK_ERROR_INITIALIZATION_FAILED:
      return "initialization failed";
    case VK_ERROR_DEVICE_LOST:
      return "device lost";
    case VK_ERROR_MEMORY_MAP_FAILED:
      return "memory map failed";
    case VK_ERROR_LAYER_NOT_PRESENT:
      return "layer not present";
    case VK_ERROR_EXTENSION_NOT_PRESENT:
      return "extension not present";
    case VK_ERROR_FEATURE_NOT_PRESENT:
      return "feature not present";
    case VK_ERROR_INCOMPATIBLE_DRIVER:
      return "incompatible driver (no Vulkan driver installed?)";
    case VK_ERROR_TOO_MANY_OBJECTS:
      return "too many objects";
    default:
      return "VkResult " + std::to_string(int(r));
  }
}

bool validationRequested() {
  const char* e = std::getenv("CURVESTEREO_VULKAN_VALIDATION");
  return e && *e && std::string(e) != "0";
}

std::string Instance::create(bool validation) {
  const Loader& l = loader();
  if (!l.error.empty()) return l.error;
  uint32_t version = VK_API_VERSION_1_0;
  if (l.vkEnumerateInstanceVersion) l.vkEnumerateInstanceVersion(&version);
  if (version < VK_API_VERSION_1_2) return "the Vulkan loader is older than 1.2";

  std::vector<const char*> layers, extensions;
  if (validation) {
    uint32_t n = 0;
    l.vkEnumerateInstanceLayerProperties(&n, nullptr);
    std::vector<VkLayerProperties> props(n);
    l.vkEnumerateInstanceLayerProperties(&n, props.data());
    bool haveLayer = false;
    for (const auto& p : props) haveLayer |= std::strcmp(p.layerName, kValidationLayer) == 0;
    uint32_t ne = 0;
    l.vkEnumerateInstanceExtensionProperties(nullptr, &ne, nullptr);
    std::vector<VkExtensionProperties> exts(ne);
    l.vkEnumerateInstanceExtensionProperties(nullptr, &ne, exts.data());
    bool haveDebugUtils = false;
    for (const auto& e : exts) haveDebugUtils |= std::strcmp(e.extensionName, VK_EXT_DEBUG_UTILS_EXTENSION_NAME) == 0;
    if (haveLayer && haveDebugUtils) {
      layers.push_back(kValidationLayer);
      extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
    }
    gLayerActive = haveLayer && haveDebugUtils;
    if (!gLayerActive)
      std::fprintf(stderr, "curvestereo: Vulkan validation asked for but %s is not installed\n", kValidationLayer);
  }

  auto app = vkStruct<VkApplicationInfo>(VK_STRUCTURE_TYPE_APPLICATION_INFO);
  app.pApplicationName = "curvestereo";
  app.pEngineName = "curvestereo";
  app.apiVersion = VK_API_VERSION_1_2;
  auto ci = vkStruct<VkInstanceCreateInfo>(VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO);
  ci.pApplicationInfo = &app;
  ci.enabledLayerCount = uint32_t(layers.size());
  ci.ppEnabledLayerNames = layers.data();
  ci.enabledExtensionCount = uint32_t(extensions.size());
  ci.ppEnabledExtensionNames = extensions.data();
  auto dci = vkStruct<VkDebugUtilsMessengerCreateInfoEXT>(VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT);
  dci.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  dci.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                    VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
  dci.pfnUserCallback = debugCallback;
  if (!layers.empty()) ci.pNext = &dci;  // also covers vkCreateInstance / vkDestroyInstance
  VkResult r = l.vkCreateInstance(&ci, nullptr, &instance);
  if (r != VK_SUCCESS) {
    instance = VK_NULL_HANDLE;
    return r == VK_ERROR_INCOMPATIBLE_DRIVER ? "no Vulkan driver" : "vkCreateInstance failed: " + resultText(r);
  }
  fn.load(instance);
  if (!layers.empty() && fn.vkCreateDebugUtilsMessengerEXT)
    fn.vkCreateDebugUtilsMessengerEXT(instance, &dci, nullptr, &messenger);
  return "";
}

const char* typeName(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
      return "discrete GPU";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
      return "integrated GPU";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
      return "virtual GPU";
    case VK_PHYSICAL_DEVICE_TYPE_CPU:
      return "CPU";
    default:
      return "other";
  }
}

std::vector<Candidate> candidates(const Instance& inst) {
  uint32_t n = 0;
  inst.fn.vkEnumeratePhysicalDevices(inst.instance, &n, nullptr);
  std::vector<VkPhysicalDevice> devices(n);
  if (n) inst.fn.vkEnumeratePhysicalDevices(inst.instance, &n, devices.data());
  std::vector<Candidate> out;
  for (VkPhysicalDevice d : devices) {
    Candidate c;
    c.device = d;
    inst.fn.vkGetPhysicalDeviceProperties(d, &c.props);
    uint32_t ne = 0;
    inst.fn.vkEnumerateDeviceExtensionProperties(d, nullptr, &ne, nullptr);
    std::vector<VkExtensionProperties> exts(ne);
    if (ne) inst.fn.vkEnumerateDeviceExtensionProperties(d, nullptr, &ne, exts.data());
    bool haveAtomicFloat = false;
    for (const auto& e : exts)
      haveAtomicFloat |= std::strcmp(e.extensionName, VK_EXT_SHADER_ATOMIC_FLOAT_EXTENSION_NAME) == 0;
    auto af = vkStruct<VkPhysicalDeviceShaderAtomicFloatFeaturesEXT>(
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_ATOMIC_FLOAT_FEATURES_EXT);
    auto f12 = vkStruct<VkPhysicalDeviceVulkan12Features>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES);
    f12.pNext = haveAtomicFloat ? &af : nullptr;  // a struct of an extension the device lacks is invalid
    auto f2 = vkStruct<VkPhysicalDeviceFeatures2>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2);
    f2.pNext = &f12;
    if (c.props.apiVersion >= VK_API_VERSION_1_2) inst.fn.vkGetPhysicalDeviceFeatures2(d, &f2);
    c.float64 = f2.features.shaderFloat64;
    c.int64 = f2.features.shaderInt64;
    c.atomicFloatAdd = haveAtomicFloat && af.shaderBufferFloat32AtomicAdd;
    uint32_t nq = 0;
    inst.fn.vkGetPhysicalDeviceQueueFamilyProperties(d, &nq, nullptr);
    std::vector<VkQueueFamilyProperties> qf(nq);
    inst.fn.vkGetPhysicalDeviceQueueFamilyProperties(d, &nq, qf.data());
    for (uint32_t i = 0; i < nq; ++i)
      if ((qf[i].queueFlags & VK_QUEUE_COMPUTE_BIT) && qf[i].queueCount > 0) c.computeFamilies.push_back(i);
    if (c.props.apiVersion < VK_API_VERSION_1_2)
      c.unusable = "supports only Vulkan < 1.2";
    else if (!f12.bufferDeviceAddress)
      c.unusable = "lacks bufferDeviceAddress";
    else if (c.computeFamilies.empty())
      c.unusable = "has no compute queue";
    else if (c.props.limits.maxPushConstantsSize < 128)
      c.unusable = "has < 128 bytes of push constants";
    out.push_back(c);
  }
  return out;
}

const Candidate* selectDevice(const std::vector<Candidate>& all, const std::string& spec, bool autoMode,
                              std::string& why) {
  if (all.empty()) {
    why = "no Vulkan device";
    return nullptr;
  }
  std::string list;
  for (size_t i = 0; i < all.size(); ++i)
    list += (i ? ", " : "") + std::to_string(i) + ": " + all[i].props.deviceName + " (" +
            typeName(all[i].props.deviceType) + ")";
  const Candidate* pick = nullptr;
  if (spec.empty()) {
    for (const Candidate& c : all)
      if (c.unusable.empty() && (!pick || typeRank(c.props.deviceType) < typeRank(pick->props.deviceType))) pick = &c;
    if (!pick) {
      why = "no usable Vulkan device (" + std::string(all[0].props.deviceName) + " " + all[0].unusable + ")";
      return nullptr;
    }
  } else if (std::all_of(spec.begin(), spec.end(),
                         [](char ch) { return std::isdigit(static_cast<unsigned char>(ch)); })) {
    const size_t index = std::stoul(spec);
    if (index >= all.size()) {
      why = "no Vulkan device " + spec + " (devices: " + list + ")";
      return nullptr;
    }
    pick = &all[index];
  } else {
    for (const Candidate& c : all)
      if (lower(c.props.deviceName).find(lower(spec)) != std::string::npos) {
        pick = &c;
        break;
      }
    if (!pick) {
      why = "no Vulkan device matches '" + spec + "' (devices: " + list + ")";
      return nullptr;
    }
  }
  if (!pick->unusable.empty()) {
    why = std::string("Vulkan device ") + pick->props.deviceName + " " + pick->unusable;
    return nullptr;
  }
  if (autoMode && spec.empty() && pick->props.deviceType != VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU) {
    why = std::string("only a non-discrete Vulkan device (") + pick->props.deviceName + ", " +
          typeName(pick->props.deviceType) + "); ask for it with --backend vulkan";
    return nullptr;
  }
  why.clear();
  return pick;
}

std::string probe(const std::string& device, bool autoMode) {
  static std::mutex mutex;
  static std::map<std::pair<std::string, bool>, std::string> cache;
  std::lock_guard<std::mutex> lock(mutex);
  auto it = cache.find({device, autoMode});
  if (it != cache.end()) return it->second;
  std::string why;
  {
    Instance inst;
    why = inst.create(false);
    if (why.empty()) selectDevice(candidates(inst), device, autoMode, why);
  }
  cache[{device, autoMode}] = why;
  return why;
}

}  // namespace vk

std::string probeVulkan(const std::string& device) { return vk::probe(device, false); }
std::string probeVulkanAuto(const std::string& device) { return vk::probe(device, true); }

long long vulkanValidationMessageCount() { return vk::gValidationCount.load(); }
std::string vulkanValidationLastMessage() {
  std::lock_guard<std::mutex> lock(vk::gValidationMutex);
  return vk::gLastValidationMessage;
}
bool vulkanValidationLayerActive() { return vk::gLayerActive.load(); }

}  // namespace cs

namespace cs::vk {

namespace {

std::mutex sharingLock;  // the two registries below
std::weak_ptr<Instance> liveInstance;
std::map<VkPhysicalDevice, std::weak_ptr<SharedDevice>> liveDevices;

}  // namespace

std::shared_ptr<Instance> sharedInstance() {
  std::lock_guard<std::mutex> lock(sharingLock);
  if (std::shared_ptr<Instance> alive = liveInstance.lock()) return alive;
  auto made = std::make_shared<Instance>();
  const std::string why = made->create(validationRequested());
  if (!why.empty()) throw Error("vulkan backend: " + why);
  liveInstance = made;
  return made;
}

SharedDevice::~SharedDevice() {
  if (!device || abandoned) return;
  instance->fn.vkDeviceWaitIdle(device);
  instance->fn.vkDestroyDevice(device, nullptr);
}

std::shared_ptr<SharedDevice> sharedDevice(const std::shared_ptr<Instance>& instance, const Candidate& c,
                                           SharedDevice::Queue*& queue) {
  std::lock_guard<std::mutex> lock(sharingLock);
  std::shared_ptr<SharedDevice> d = liveDevices[c.device].lock();
  if (!d) {
    d = std::make_shared<SharedDevice>();
    d->instance = instance;
    // One queue per family: NVIDIA's driver time-slices a family's queues rather than running
    // them side by side, so more queues of one family only cost switches (eight rig
    // directions on 16 + 8 queues: 31.1-31.3 ms a frame on an H100; on one queue of each
    // family: 25.9-26.9 ms). Two families do overlap.
    const float priority = 1.f;
    std::vector<VkDeviceQueueCreateInfo> qcis;
    for (uint32_t family : c.computeFamilies) {
      auto qci = vkStruct<VkDeviceQueueCreateInfo>(VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO);
      qci.queueFamilyIndex = family;
      qci.queueCount = 1;
      qci.pQueuePriorities = &priority;
      qcis.push_back(qci);
    }
    auto f12 = vkStruct<VkPhysicalDeviceVulkan12Features>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES);
    f12.bufferDeviceAddress = VK_TRUE;
    auto f2 = vkStruct<VkPhysicalDeviceFeatures2>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2);
    f2.pNext = &f12;
    f2.features.shaderFloat64 = c.float64 ? VK_TRUE : VK_FALSE;  // triangulate.comp uses it
    f2.features.shaderInt64 = c.int64 ? VK_TRUE : VK_FALSE;
    // panorama_splat.comp's sums in a native float atomic add where the device has one: its
    // compare-and-swap loop made the splat 3.5 to 4.5 times CUDA's (23-30 against 6.6 ms, H200).
    auto af = vkStruct<VkPhysicalDeviceShaderAtomicFloatFeaturesEXT>(
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_ATOMIC_FLOAT_FEATURES_EXT);
    af.shaderBufferFloat32AtomicAdd = VK_TRUE;
    std::vector<const char*> extensions;
    if (c.atomicFloatAdd) {
      f12.pNext = &af;
      extensions.push_back(VK_EXT_SHADER_ATOMIC_FLOAT_EXTENSION_NAME);
    }
    d->atomicFloatAdd = c.atomicFloatAdd;
    auto dci = vkStruct<VkDeviceCreateInfo>(VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO);
    dci.pNext = &f2;
    dci.queueCreateInfoCount = uint32_t(qcis.size());
    dci.pQueueCreateInfos = qcis.data();
    dci.enabledExtensionCount = uint32_t(extensions.size());
    dci.ppEnabledExtensionNames = extensions.data();
    const VkResult r = instance->fn.vkCreateDevice(c.device, &dci, nullptr, &d->device);
    if (r != VK_SUCCESS) {
      d->device = VK_NULL_HANDLE;
      throw Error("vulkan backend: vkCreateDevice failed: " + resultText(r));
    }
    for (uint32_t family : c.computeFamilies) {
      auto q = std::make_unique<SharedDevice::Queue>();
      q->family = family;
      instance->fn.vkGetDeviceQueue(d->device, family, 0, &q->queue);
      d->queues.push_back(std::move(q));
    }
    liveDevices[c.device] = d;
  }
  queue = d->queues[d->queuesTaken++ % d->queues.size()].get();
  return d;
}

int sharedDevicesAlive() {
  std::lock_guard<std::mutex> lock(sharingLock);
  int alive = 0;
  for (const auto& [phys, d] : liveDevices) alive += !d.expired();
  return alive;
}

}  // namespace cs::vk

namespace cs {
int vulkanDevicesAlive() { return vk::sharedDevicesAlive(); }
}  // namespace cs
