// The Vulkan backend (see vulkan_backend.hpp). The loader is opened at run time (dlopen),
// so a build with Vulkan runs on machines without it: the backend then reports
// "no Vulkan loader" and auto falls back.
#define VK_NO_PROTOTYPES
#include "vulkan_backend.hpp"

#include <dlfcn.h>
#include <vulkan/vulkan.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <tuple>
#include <type_traits>
#include <vector>

#include "curvestereo/camera.hpp"
#include "curvestereo/camera_models.hpp"
#include "curvestereo/image.hpp"
#include "normalise.hpp"
#include "shader_table.hpp"

namespace cs {

namespace {

// ---------------------------------------------------------------------------------------
// Loader and function table.

#define CS_VK_GLOBAL_FNS(X)                 \
  X(vkCreateInstance)                       \
  X(vkEnumerateInstanceLayerProperties)     \
  X(vkEnumerateInstanceExtensionProperties) \
  X(vkEnumerateInstanceVersion)

#define CS_VK_INSTANCE_FNS(X)                 \
  X(vkDestroyInstance)                        \
  X(vkEnumeratePhysicalDevices)               \
  X(vkGetPhysicalDeviceProperties)            \
  X(vkGetPhysicalDeviceProperties2)           \
  X(vkGetPhysicalDeviceFeatures2)             \
  X(vkGetPhysicalDeviceQueueFamilyProperties) \
  X(vkGetPhysicalDeviceMemoryProperties)      \
  X(vkCreateDevice)                           \
  X(vkDestroyDevice)                          \
  X(vkGetDeviceQueue)                         \
  X(vkCreateBuffer)                           \
  X(vkDestroyBuffer)                          \
  X(vkGetBufferMemoryRequirements)            \
  X(vkAllocateMemory)                         \
  X(vkFreeMemory)                             \
  X(vkBindBufferMemory)                       \
  X(vkMapMemory)                              \
  X(vkUnmapMemory)                            \
  X(vkGetBufferDeviceAddress)                 \
  X(vkCreateShaderModule)                     \
  X(vkDestroyShaderModule)                    \
  X(vkCreatePipelineLayout)                   \
  X(vkDestroyPipelineLayout)                  \
  X(vkCreateComputePipelines)                 \
  X(vkDestroyPipeline)                        \
  X(vkCreateCommandPool)                      \
  X(vkDestroyCommandPool)                     \
  X(vkAllocateCommandBuffers)                 \
  X(vkBeginCommandBuffer)                     \
  X(vkEndCommandBuffer)                       \
  X(vkResetCommandBuffer)                     \
  X(vkCmdBindPipeline)                        \
  X(vkCmdPushConstants)                       \
  X(vkCmdDispatch)                            \
  X(vkCmdPipelineBarrier)                     \
  X(vkCmdCopyBuffer)                          \
  X(vkCmdFillBuffer)                          \
  X(vkCmdWriteTimestamp)                      \
  X(vkCmdResetQueryPool)                      \
  X(vkCreateQueryPool)                        \
  X(vkDestroyQueryPool)                       \
  X(vkGetQueryPoolResults)                    \
  X(vkCreateFence)                            \
  X(vkDestroyFence)                           \
  X(vkWaitForFences)                          \
  X(vkResetFences)                            \
  X(vkQueueSubmit)                            \
  X(vkDeviceWaitIdle)

#define CS_VK_DECLARE(name) PFN_##name name = nullptr;

struct Loader {
  void* lib = nullptr;
  PFN_vkGetInstanceProcAddr getInstanceProcAddr = nullptr;
  CS_VK_GLOBAL_FNS(CS_VK_DECLARE)
  std::string error;
};

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

struct InstanceFns {
  CS_VK_INSTANCE_FNS(CS_VK_DECLARE)
  PFN_vkCreateDebugUtilsMessengerEXT vkCreateDebugUtilsMessengerEXT = nullptr;
  PFN_vkDestroyDebugUtilsMessengerEXT vkDestroyDebugUtilsMessengerEXT = nullptr;

  void load(VkInstance instance) {
    auto get = loader().getInstanceProcAddr;
#define CS_VK_LOAD(name) name = reinterpret_cast<PFN_##name>(get(instance, #name));
    CS_VK_INSTANCE_FNS(CS_VK_LOAD)
    CS_VK_LOAD(vkCreateDebugUtilsMessengerEXT)
    CS_VK_LOAD(vkDestroyDebugUtilsMessengerEXT)
#undef CS_VK_LOAD
  }
};

// A Vulkan struct zeroed, with its sType set.
template <class T>
T vkStruct(VkStructureType type) {
  T t{};
  t.sType = type;
  return t;
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

// ---------------------------------------------------------------------------------------
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

bool validationRequested() {
  const char* e = std::getenv("CURVESTEREO_VULKAN_VALIDATION");
  return e && *e && std::string(e) != "0";
}

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

// ---------------------------------------------------------------------------------------
// Instance and device selection.

struct Instance {
  VkInstance instance = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
  InstanceFns fn;

  Instance() = default;
  Instance(const Instance&) = delete;
  Instance& operator=(const Instance&) = delete;
  ~Instance() {
    if (!instance) return;
    if (messenger && fn.vkDestroyDebugUtilsMessengerEXT)
      fn.vkDestroyDebugUtilsMessengerEXT(instance, messenger, nullptr);
    fn.vkDestroyInstance(instance, nullptr);
  }

  // "" on success, else why not.
  std::string create(bool validation) {
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
    dci.messageSeverity =
        VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
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
};

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

struct Candidate {
  VkPhysicalDevice device = VK_NULL_HANDLE;
  VkPhysicalDeviceProperties props{};
  uint32_t queueFamily = 0;
  bool float64 = false, int64 = false;
  std::string unusable;  // why this device cannot run the backend ("" if it can)
};

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
    auto f12 = vkStruct<VkPhysicalDeviceVulkan12Features>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES);
    auto f2 = vkStruct<VkPhysicalDeviceFeatures2>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2);
    f2.pNext = &f12;
    if (c.props.apiVersion >= VK_API_VERSION_1_2) inst.fn.vkGetPhysicalDeviceFeatures2(d, &f2);
    c.float64 = f2.features.shaderFloat64;
    c.int64 = f2.features.shaderInt64;
    uint32_t nq = 0;
    inst.fn.vkGetPhysicalDeviceQueueFamilyProperties(d, &nq, nullptr);
    std::vector<VkQueueFamilyProperties> qf(nq);
    inst.fn.vkGetPhysicalDeviceQueueFamilyProperties(d, &nq, qf.data());
    bool compute = false;
    for (uint32_t i = 0; i < nq && !compute; ++i)
      if (qf[i].queueFlags & VK_QUEUE_COMPUTE_BIT) compute = true, c.queueFamily = i;
    if (c.props.apiVersion < VK_API_VERSION_1_2)
      c.unusable = "supports only Vulkan < 1.2";
    else if (!f12.bufferDeviceAddress)
      c.unusable = "lacks bufferDeviceAddress";
    else if (!compute)
      c.unusable = "has no compute queue";
    else if (c.props.limits.maxPushConstantsSize < 128)
      c.unusable = "has < 128 bytes of push constants";
    out.push_back(c);
  }
  return out;
}

// The device `spec` selects, or an error. autoMode: refuse devices that are not GPUs.
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

// ---------------------------------------------------------------------------------------
// Parameter blocks the camera shaders read (mirrors of the GLSL structs, std430).

template <class S>
struct VkCam {
  int32_t model, width, height, pad;
  S p[8];
  S d[4];
};
static_assert(sizeof(VkCam<double>) == 112 && sizeof(VkCam<float>) == 64, "VkCam must match the GLSL Cam");

template <class S>
struct VkFieldsParams {
  VkCam<S> cam0, cam1;
  S R[9];
  S tPrime[3];
  S tDir[3];
  S halfFov;
  S epipole;
  int32_t useFov;
};

template <class S>
struct VkTriangulateParams {
  VkCam<S> cam0;
  S tPrime[3];
};

template <class S>
struct VkSweepParams {
  VkCam<S> cam;
  S t[3];
  S qMax;
};

template <class S>
VkCam<S> toVkCam(const CameraParams& c) {
  VkCam<S> out{};
  out.model = c.model;
  out.width = c.width;
  out.height = c.height;
  for (int i = 0; i < 8; ++i) out.p[i] = S(c.params[i]);
  const double* p = c.params;
  switch (CameraModel(c.model)) {
    case CameraModel::KannalaBrandt4: {
      models::KannalaBrandt4<S> m(p);
      out.d[0] = m.thetaMax;
      out.d[1] = m.radiusMax;
      break;
    }
    case CameraModel::Unified:
      out.d[0] = models::Unified<S>(p).w;
      break;
    case CameraModel::ExtendedUnified:
      out.d[0] = models::ExtendedUnified<S>(p).w;
      break;
    case CameraModel::DoubleSphere:
      out.d[0] = models::DoubleSphere<S>(p).w2;
      break;
    case CameraModel::PinholeRadtan:
      break;
    default:
      throw Error("vulkan backend: unknown camera model " + std::to_string(c.model));
  }
  return out;
}

// ---------------------------------------------------------------------------------------
// Shaders and push constants (mirrors of each shader's push_constant block).

enum Shader {
  kWarp,
  kDownsample,
  kUpsample,
  kNormaliseMoments,
  kNormalise,
  kTensorBlur,
  kTensor,
  kTensorSteps,
  kWarpDerivatives,
  kDual,
  kPrimal,
  kMedian,
  kAccumulate,
  kFields32,
  kFields64,
  kTriangulate32,
  kTriangulate64,
  kSweepWarp32,
  kSweepWarp64,
  kSweepCost,
  kSweepAggregate,
  kSweepSelect32,
  kSweepSelect64,
  kSweepInitialise32,
  kSweepInitialise64,
  kShaderCount
};
const char* const kShaderNames[kShaderCount] = {"warp",
                                                "downsample",
                                                "upsample",
                                                "normalise_moments",
                                                "normalise",
                                                "structure_tensor_blur",
                                                "structure_tensor",
                                                "structure_tensor_steps",
                                                "warp_derivatives",
                                                "primal_dual_dual",
                                                "primal_dual_primal",
                                                "median",
                                                "accumulate",
                                                "fields_f32",
                                                "fields_f64",
                                                "triangulate_f32",
                                                "triangulate_f64",
                                                "sweep_warp_f32",
                                                "sweep_warp_f64",
                                                "sweep_cost",
                                                "sweep_aggregate",
                                                "sweep_select_f32",
                                                "sweep_select_f64",
                                                "sweep_initialise_f32",
                                                "sweep_initialise_f64"};

constexpr uint32_t kPushBytes = 128;
constexpr uint32_t kGroup = 16;

using Addr = uint64_t;

struct PcWarp {
  Addr dst, src, flow;
  int32_t w, h, nc, sw, sh;
};
struct PcDownsample {
  Addr dst, src;
  int32_t w, h, nc, sw, sh, radius;
  float scale, sigma;
};
struct PcUpsample {
  Addr dst, src;
  int32_t w, h, nc, sw, sh;
  float scale, valueScale;
};
struct PcBlur {
  Addr dst, src;
  int32_t w, h, radius, dir;
  float sigma;
};
struct PcTensor {
  Addr tensor, smoothed;
  int32_t w, h;
  float beta, eta, wMin;
};
struct PcSteps {
  Addr steps, tensor, mask;
  int32_t w, h;
  float alpha0, alpha1;
};
struct PcWarpDerivatives {
  Addr u0, iu, iz, tangent, i0, i1, trajectory, w, u, mask, confidence;  // confidence: mask when absent
  int32_t width, height, hasConfidence;
  float weightFloor;
};
struct PcDual {
  Addr uBar, vBar, p, q, tensor, steps, mask;
  int32_t w, h;
  float sigmaScale, alpha0, alpha1;
};
struct PcPrimal {
  Addr u, uBar, v, vBar, p, q, u0, iu, iz, tensor, steps, mask;
  int32_t w, h;
  float tauScale, theta, lambda, alpha0, alpha1;
};
struct PcMedian {
  Addr dst, src, mask;
  int32_t w, h;
};
struct PcAccumulate {
  Addr u, w, u0, tangent, mask;
  int32_t width, height;
  float duMax;
};
struct PcFields {
  Addr mask, calibration, trajectory, params;
  int32_t w, h;
};
struct PcTriangulate {
  Addr radial, points, w, mask, params;
  int32_t width, height;
};
struct PcSweepWarp {
  Addr volume, image, mask, params;
  int32_t width, height, planes;
};
struct PcSweepCost {
  Addr costs, reference, volume, mask;
  int32_t width, height, planes, radius;
  float flatVariance;
};
struct PcSweepAggregate {
  Addr aggregated, costs, mask;
  int32_t width, height, planes, direction;
  float p1, p2;
};
struct PcSweepSelect {
  Addr best, aggregated, costs, mask, params;
  int32_t width, height, planes;
};
struct PcSweepInitialise {
  Addr u, w, confidence, best, other, mask, params;
  int32_t width, height;
  float tolerancePx, acceptConfidence;
  int32_t pass, planes;
};
static_assert(sizeof(PcPrimal) <= kPushBytes, "push constants exceed the guaranteed 128 bytes");

// ---------------------------------------------------------------------------------------

class VulkanBackend final : public Backend {
 public:
  explicit VulkanBackend(const std::string& spec);
  ~VulkanBackend() override;

  std::string name() const override { return "vulkan"; }
  std::string device() const override { return description_; }
  unsigned long long memoryBytes() const override;

  void synchronize() override;
  void beginFrame() override;
  void endFrame() override;
  bool canReplayFrame() const override { return frameValid_; }
  void replayFrame() override;
  void beginStage(const std::string& name) override;
  std::vector<StageTime> takeStageTimes() override;

 protected:
  Buffer doCreate(int width, int height, int channels) override;
  void doUpload(const Buffer& dst, const float* host) override;
  void doDownload(const Buffer& src, float* host) override;
  void doFill(const Buffer& dst, float value) override;
  void doCopy(const Buffer& dst, const Buffer& src) override;

  void doFields(const Buffer& mask, const Buffer& calibration, const Buffer& trajectory,
                const FieldsParams& params) override;
  void doWarp(const Buffer& dst, const Buffer& src, const Buffer& flow) override;
  void doDownsample(const Buffer& dst, const Buffer& src, float scale) override;
  void doUpsample(const Buffer& dst, const Buffer& src, float scale, float valueScale) override;
  void doNormalise(const Buffer& dst, const Buffer& moments, const Buffer& src, const Buffer& mask,
                   const NormaliseParams& params) override;
  void doStructureTensor(const Buffer& tensor, const Buffer& steps, const Buffer& image, const Buffer& mask,
                         const TensorParams& params) override;
  void doWarpDerivatives(const DataTermBuffers& data, const Buffer& tangent, const Buffer& i0, const Buffer& i1,
                         const Buffer& trajectory, const Buffer& w, const Buffer& u, const Buffer& mask,
                         const Buffer& confidence, float weightFloor) override;
  void doPrimalDual(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor, const Buffer& steps,
                    const Buffer& mask, const PrimalDualParams& params) override;
  void doMedian(const Buffer& dst, const Buffer& src, const Buffer& mask) override;
  void doAccumulate(const Buffer& u, const Buffer& w, const Buffer& u0, const Buffer& tangent, const Buffer& mask,
                    float duMax) override;
  void doSweepWarp(const Buffer& volume, const Buffer& image, const Buffer& mask, const SweepParams& p) override;
  void doSweepCost(const Buffer& costs, const Buffer& reference, const Buffer& volume, const Buffer& mask,
                   const SweepParams& p) override;
  void doSweepAggregate(const Buffer& aggregated, const Buffer& costs, const Buffer& mask,
                        const SweepParams& p) override;
  void doSweepSelect(const Buffer& best, const Buffer& aggregated, const Buffer& costs, const Buffer& mask,
                     const SweepParams& p) override;
  void doSweepInitialise(const Buffer& u, const Buffer& w, const Buffer& confidence, const Buffer& best,
                         const Buffer& other, const Buffer& mask, const SweepParams& p,
                         const ConsistencyParams& c) override;
  void doTriangulate(const Buffer& radial, const Buffer& points, const Buffer& w, const Buffer& mask,
                     const CameraParams& cam0, const double tPrime[3]) override;

 private:
  struct Arena {
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    VkDeviceAddress address = 0;
    VkDeviceSize size = 0, used = 0;
    void* mapped = nullptr;
  };
  struct Alloc {
    int arena;
    VkDeviceSize offset, bytes;
  };

  void check(VkResult r, const char* what);
  void ensureUsable() const;
  uint32_t memoryType(uint32_t bits, VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred) const;
  Arena makeBuffer(VkDeviceSize bytes, bool hostVisible);
  void destroyBuffer(Arena& a);
  const Alloc& alloc(const Buffer& b) const;
  Addr addr(const Buffer& b) const;
  Addr paramBlock(const void* data, size_t bytes);
  Addr sweepParamBlock(const SweepParams& p);
  VkPipeline pipeline(Shader s);

  VkCommandBuffer recorder();
  void barrier(VkCommandBuffer cb);
  void flush();
  void waitFence(VkFence fence, const char* what);
  void abortFrameRecording();
  // Submits one ended command buffer, signalling fence when done.
  void submit(VkCommandBuffer cb, VkFence fence);
  // A w x h grid of pixels in the 16 x 16 work groups of common.glsl.
  template <class PC>
  void dispatch(Shader s, const PC& pc, int w, int h);
  // groupsX x groupsY work groups, for shaders that map their invocations otherwise.
  template <class PC>
  void dispatchGroups(Shader s, const PC& pc, uint32_t groupsX, uint32_t groupsY);
  Buffer scratch(int slot, int w, int h);

  std::string description_;
  Instance inst_;
  VkPhysicalDevice phys_ = VK_NULL_HANDLE;
  VkPhysicalDeviceProperties props_{};
  VkPhysicalDeviceMemoryProperties memProps_{};
  bool float64_ = false;
  VkDevice dev_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  uint32_t queueFamily_ = 0;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  VkCommandBuffer immCmd_ = VK_NULL_HANDLE, frameCmd_ = VK_NULL_HANDLE;
  VkFence immFence_ = VK_NULL_HANDLE, frameFence_ = VK_NULL_HANDLE;
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkPipeline pipelines_[kShaderCount] = {};
  VkQueryPool queryPool_ = VK_NULL_HANDLE;
  uint32_t queryCapacity_ = 0, queryCount_ = 0;
  uint64_t timestampMask_ = ~0ull;
  std::vector<std::string> stampNames_;

  std::vector<Arena> arenas_;
  std::vector<Alloc> allocs_;
  Arena staging_, params_;
  VkDeviceSize paramsUsed_ = 0;
  unsigned long long allocatedBytes_ = 0;
  std::map<std::string, VkDeviceSize> paramCache_;
  std::map<std::tuple<int, int, int>, Buffer> scratch_;

  bool immRecording_ = false, immInFlight_ = false, frameInFlight_ = false;
  bool recordingFrame_ = false, frameValid_ = false, frameHasTimestamps_ = false;
  bool lost_ = false, hung_ = false;
  uint64_t timeoutNs_ = 120ull * 1000 * 1000 * 1000;
};

void VulkanBackend::check(VkResult r, const char* what) {
  if (r == VK_SUCCESS) return;
  if (r == VK_ERROR_DEVICE_LOST) lost_ = true;
  throw Error(std::string("vulkan backend: ") + what + " failed: " + resultText(r));
}

void VulkanBackend::ensureUsable() const {
  if (hung_) throw Error("vulkan backend: the device stopped responding earlier; create a new backend");
  if (lost_) throw Error("vulkan backend: the device was lost earlier; create a new backend");
}

VulkanBackend::VulkanBackend(const std::string& spec) {
  std::string why = inst_.create(validationRequested());
  if (!why.empty()) throw Error("vulkan backend: " + why);
  const std::vector<Candidate> all = candidates(inst_);
  const Candidate* c = selectDevice(all, spec, false, why);
  if (!c) throw Error("vulkan backend: " + why);
  phys_ = c->device;
  props_ = c->props;
  queueFamily_ = c->queueFamily;
  const char* forceFloat = std::getenv("CURVESTEREO_VULKAN_FLOAT_MODELS");
  float64_ = c->float64 && !(forceFloat && *forceFloat && std::string(forceFloat) != "0");
  if (const char* t = std::getenv("CURVESTEREO_VULKAN_TIMEOUT_S"))
    timeoutNs_ = uint64_t(std::max(1.0, std::atof(t)) * 1e9);
  inst_.fn.vkGetPhysicalDeviceMemoryProperties(phys_, &memProps_);

  auto driver = vkStruct<VkPhysicalDeviceDriverProperties>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES);
  auto p2 = vkStruct<VkPhysicalDeviceProperties2>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2);
  p2.pNext = &driver;
  inst_.fn.vkGetPhysicalDeviceProperties2(phys_, &p2);
  description_ = std::string(props_.deviceName) + " (" + typeName(props_.deviceType) + ", Vulkan " +
                 std::to_string(VK_API_VERSION_MAJOR(props_.apiVersion)) + "." +
                 std::to_string(VK_API_VERSION_MINOR(props_.apiVersion)) + "." +
                 std::to_string(VK_API_VERSION_PATCH(props_.apiVersion)) + ", " + driver.driverName + " " +
                 driver.driverInfo + (float64_ ? ", camera models in double" : ", camera models in float") + ")";

  const float priority = 1.f;
  auto qci = vkStruct<VkDeviceQueueCreateInfo>(VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO);
  qci.queueFamilyIndex = queueFamily_;
  qci.queueCount = 1;
  qci.pQueuePriorities = &priority;
  auto f12 = vkStruct<VkPhysicalDeviceVulkan12Features>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES);
  f12.bufferDeviceAddress = VK_TRUE;
  auto f2 = vkStruct<VkPhysicalDeviceFeatures2>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2);
  f2.pNext = &f12;
  f2.features.shaderFloat64 = float64_ ? VK_TRUE : VK_FALSE;
  f2.features.shaderInt64 = c->int64 ? VK_TRUE : VK_FALSE;
  auto dci = vkStruct<VkDeviceCreateInfo>(VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO);
  dci.pNext = &f2;
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &qci;
  check(inst_.fn.vkCreateDevice(phys_, &dci, nullptr, &dev_), "vkCreateDevice");
  inst_.fn.vkGetDeviceQueue(dev_, queueFamily_, 0, &queue_);

  auto pci = vkStruct<VkCommandPoolCreateInfo>(VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO);
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = queueFamily_;
  check(inst_.fn.vkCreateCommandPool(dev_, &pci, nullptr, &pool_), "vkCreateCommandPool");
  auto cai = vkStruct<VkCommandBufferAllocateInfo>(VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO);
  cai.commandPool = pool_;
  cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  cai.commandBufferCount = 1;
  check(inst_.fn.vkAllocateCommandBuffers(dev_, &cai, &immCmd_), "vkAllocateCommandBuffers");
  check(inst_.fn.vkAllocateCommandBuffers(dev_, &cai, &frameCmd_), "vkAllocateCommandBuffers");
  auto fci = vkStruct<VkFenceCreateInfo>(VK_STRUCTURE_TYPE_FENCE_CREATE_INFO);
  check(inst_.fn.vkCreateFence(dev_, &fci, nullptr, &immFence_), "vkCreateFence");
  check(inst_.fn.vkCreateFence(dev_, &fci, nullptr, &frameFence_), "vkCreateFence");

  VkPushConstantRange range{VK_SHADER_STAGE_COMPUTE_BIT, 0, kPushBytes};
  auto lci = vkStruct<VkPipelineLayoutCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO);
  lci.pushConstantRangeCount = 1;
  lci.pPushConstantRanges = &range;
  check(inst_.fn.vkCreatePipelineLayout(dev_, &lci, nullptr, &layout_), "vkCreatePipelineLayout");

  // Timestamps, where the queue has them.
  uint32_t nq = 0;
  inst_.fn.vkGetPhysicalDeviceQueueFamilyProperties(phys_, &nq, nullptr);
  std::vector<VkQueueFamilyProperties> qf(nq);
  inst_.fn.vkGetPhysicalDeviceQueueFamilyProperties(phys_, &nq, qf.data());
  const uint32_t bits = qf[queueFamily_].timestampValidBits;
  if (bits > 0 && props_.limits.timestampPeriod > 0) {
    timestampMask_ = bits >= 64 ? ~0ull : ((1ull << bits) - 1);
    queryCapacity_ = 16384;
    auto qpci = vkStruct<VkQueryPoolCreateInfo>(VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO);
    qpci.queryType = VK_QUERY_TYPE_TIMESTAMP;
    qpci.queryCount = queryCapacity_;
    check(inst_.fn.vkCreateQueryPool(dev_, &qpci, nullptr, &queryPool_), "vkCreateQueryPool");
  }

  params_ = makeBuffer(1 << 20, true);
}

VulkanBackend::~VulkanBackend() {
  if (!dev_) return;
  if (hung_) return;  // work may still run on the device: leak rather than free memory in use
  inst_.fn.vkDeviceWaitIdle(dev_);
  for (VkPipeline p : pipelines_)
    if (p) inst_.fn.vkDestroyPipeline(dev_, p, nullptr);
  for (Arena& a : arenas_) destroyBuffer(a);
  destroyBuffer(staging_);
  destroyBuffer(params_);
  if (queryPool_) inst_.fn.vkDestroyQueryPool(dev_, queryPool_, nullptr);
  if (layout_) inst_.fn.vkDestroyPipelineLayout(dev_, layout_, nullptr);
  if (immFence_) inst_.fn.vkDestroyFence(dev_, immFence_, nullptr);
  if (frameFence_) inst_.fn.vkDestroyFence(dev_, frameFence_, nullptr);
  if (pool_) inst_.fn.vkDestroyCommandPool(dev_, pool_, nullptr);
  inst_.fn.vkDestroyDevice(dev_, nullptr);
}

// ---- memory ----

// The largest device-local heap (a GPU's memory; lavapipe reports system memory).
unsigned long long VulkanBackend::memoryBytes() const {
  unsigned long long best = 0;
  for (uint32_t i = 0; i < memProps_.memoryHeapCount; ++i)
    if (memProps_.memoryHeaps[i].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT)
      best = std::max<unsigned long long>(best, memProps_.memoryHeaps[i].size);
  return best;
}

uint32_t VulkanBackend::memoryType(uint32_t bits, VkMemoryPropertyFlags required,
                                   VkMemoryPropertyFlags preferred) const {
  int best = -1;
  for (uint32_t i = 0; i < memProps_.memoryTypeCount; ++i) {
    const VkMemoryPropertyFlags f = memProps_.memoryTypes[i].propertyFlags;
    if (!(bits & (1u << i)) || (f & required) != required) continue;
    if ((f & preferred) == preferred) return i;
    if (best < 0) best = int(i);
  }
  if (best < 0) throw Error("vulkan backend: no suitable memory type");
  return uint32_t(best);
}

VulkanBackend::Arena VulkanBackend::makeBuffer(VkDeviceSize bytes, bool hostVisible) {
  Arena a;
  a.size = bytes;
  auto bci = vkStruct<VkBufferCreateInfo>(VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO);
  bci.size = bytes;
  bci.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT |
              VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT;
  bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  check(inst_.fn.vkCreateBuffer(dev_, &bci, nullptr, &a.buffer), "vkCreateBuffer");
  VkMemoryRequirements req;
  inst_.fn.vkGetBufferMemoryRequirements(dev_, a.buffer, &req);
  auto flags = vkStruct<VkMemoryAllocateFlagsInfo>(VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO);
  flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
  auto mai = vkStruct<VkMemoryAllocateInfo>(VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO);
  mai.pNext = &flags;
  mai.allocationSize = req.size;
  mai.memoryTypeIndex =
      hostVisible
          ? memoryType(req.memoryTypeBits, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
                       VK_MEMORY_PROPERTY_HOST_CACHED_BIT)
          : memoryType(req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0);
  VkResult r = inst_.fn.vkAllocateMemory(dev_, &mai, nullptr, &a.memory);
  if (r != VK_SUCCESS) {
    inst_.fn.vkDestroyBuffer(dev_, a.buffer, nullptr);
    if (r == VK_ERROR_OUT_OF_DEVICE_MEMORY || r == VK_ERROR_OUT_OF_HOST_MEMORY)
      throw Error("vulkan backend: out of " + std::string(hostVisible ? "host" : "device") + " memory allocating " +
                  std::to_string(bytes >> 20) + " MiB on " + props_.deviceName);
    check(r, "vkAllocateMemory");
  }
  check(inst_.fn.vkBindBufferMemory(dev_, a.buffer, a.memory, 0), "vkBindBufferMemory");
  auto ai = vkStruct<VkBufferDeviceAddressInfo>(VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO);
  ai.buffer = a.buffer;
  a.address = inst_.fn.vkGetBufferDeviceAddress(dev_, &ai);
  if (hostVisible) check(inst_.fn.vkMapMemory(dev_, a.memory, 0, VK_WHOLE_SIZE, 0, &a.mapped), "vkMapMemory");
  return a;
}

void VulkanBackend::destroyBuffer(Arena& a) {
  if (a.mapped) inst_.fn.vkUnmapMemory(dev_, a.memory);
  if (a.buffer) inst_.fn.vkDestroyBuffer(dev_, a.buffer, nullptr);
  if (a.memory) inst_.fn.vkFreeMemory(dev_, a.memory, nullptr);
  a = Arena{};
}

Buffer VulkanBackend::doCreate(int width, int height, int channels) {
  ensureUsable();
  Buffer b{int(allocs_.size()), width, height, channels};
  // Buffers sit back to back (16-byte aligned) in large arenas, so a kernel writing past
  // its output lands in a neighbour: the guard tests see it.
  const VkDeviceSize bytes = std::max<VkDeviceSize>(4, b.count() * sizeof(float));
  const VkDeviceSize aligned = (bytes + 15) & ~VkDeviceSize(15);
  const unsigned long long heap = memoryBytes();
  if (heap && allocatedBytes_ + aligned > heap)
    throw Error("vulkan backend: out of device memory: a " + std::to_string(width) + "x" + std::to_string(height) +
                "x" + std::to_string(channels) + " buffer (" + std::to_string(bytes >> 20) +
                " MiB) does not fit in the " + std::to_string(heap >> 20) + " MiB of " + props_.deviceName);
  allocatedBytes_ += aligned;
  if (arenas_.empty() || arenas_.back().used + aligned > arenas_.back().size)
    arenas_.push_back(makeBuffer(std::max<VkDeviceSize>(VkDeviceSize(64) << 20, aligned), false));
  Arena& a = arenas_.back();
  allocs_.push_back({int(arenas_.size() - 1), a.used, bytes});
  a.used += aligned;
  frameValid_ = false;  // a new pipeline (new buffers) must not replay an old frame
  return b;
}

// Backend has checked the buffer: created here, used no larger than created.
const VulkanBackend::Alloc& VulkanBackend::alloc(const Buffer& b) const { return allocs_[size_t(b.id)]; }

Addr VulkanBackend::addr(const Buffer& b) const {
  const Alloc& a = alloc(b);
  return arenas_[size_t(a.arena)].address + a.offset;
}

// A block of kernel parameters in host-visible memory, reused for identical contents (the
// recorded frame's triangulation finds its block again every frame).
Addr VulkanBackend::paramBlock(const void* data, size_t bytes) {
  const std::string key(static_cast<const char*>(data), bytes);
  auto it = paramCache_.find(key);
  if (it != paramCache_.end()) return params_.address + it->second;
  const VkDeviceSize aligned = (bytes + 255) & ~VkDeviceSize(255);
  if (paramsUsed_ + aligned > params_.size) {
    // Full (thousands of poses): wait until no submitted work reads a block, then start over.
    flush();
    paramCache_.clear();
    paramsUsed_ = 0;
    frameValid_ = false;
  }
  std::memcpy(static_cast<char*>(params_.mapped) + paramsUsed_, data, bytes);
  paramCache_[key] = paramsUsed_;
  const Addr a = params_.address + paramsUsed_;
  paramsUsed_ += aligned;
  return a;
}

VkPipeline VulkanBackend::pipeline(Shader s) {
  if (pipelines_[s]) return pipelines_[s];
  const vk::EmbeddedShader* found = nullptr;
  for (const auto& e : vk::embeddedShaders())
    if (std::strcmp(e.name, kShaderNames[s]) == 0) found = &e;
  if (!found) throw Error(std::string("vulkan backend: shader ") + kShaderNames[s] + " is not embedded");
  auto smci = vkStruct<VkShaderModuleCreateInfo>(VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO);
  smci.codeSize = found->bytes;
  smci.pCode = found->code;
  VkShaderModule module;
  check(inst_.fn.vkCreateShaderModule(dev_, &smci, nullptr, &module), "vkCreateShaderModule");
  auto cpci = vkStruct<VkComputePipelineCreateInfo>(VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO);
  cpci.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
  cpci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  cpci.stage.module = module;
  cpci.stage.pName = "main";
  cpci.layout = layout_;
  VkResult r = inst_.fn.vkCreateComputePipelines(dev_, VK_NULL_HANDLE, 1, &cpci, nullptr, &pipelines_[s]);
  inst_.fn.vkDestroyShaderModule(dev_, module, nullptr);
  check(r, "vkCreateComputePipelines");
  return pipelines_[s];
}

// ---- command recording and submission ----

VkCommandBuffer VulkanBackend::recorder() {
  ensureUsable();
  if (recordingFrame_) return frameCmd_;
  if (!immRecording_) {
    auto bi = vkStruct<VkCommandBufferBeginInfo>(VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO);
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    check(inst_.fn.vkBeginCommandBuffer(immCmd_, &bi), "vkBeginCommandBuffer");
    immRecording_ = true;
  }
  return immCmd_;
}

// Every command depends on everything before it (kernels read what the previous ones
// wrote; transfers and dispatches interleave): one full memory barrier between them.
void VulkanBackend::barrier(VkCommandBuffer cb) {
  auto mb = vkStruct<VkMemoryBarrier>(VK_STRUCTURE_TYPE_MEMORY_BARRIER);
  mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT | VK_ACCESS_HOST_WRITE_BIT;
  mb.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_READ_BIT |
                     VK_ACCESS_TRANSFER_WRITE_BIT;
  const VkPipelineStageFlags stages = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT;
  inst_.fn.vkCmdPipelineBarrier(cb, stages | VK_PIPELINE_STAGE_HOST_BIT, stages, 0, 1, &mb, 0, nullptr, 0, nullptr);
}

void VulkanBackend::waitFence(VkFence fence, const char* what) {
  VkResult r = inst_.fn.vkWaitForFences(dev_, 1, &fence, VK_TRUE, timeoutNs_);
  if (r == VK_TIMEOUT) {
    hung_ = true;
    throw Error(std::string("vulkan backend: ") + what + " did not finish within " +
                std::to_string(timeoutNs_ / 1000000000ull) + " s (device hung?)");
  }
  check(r, what);
  check(inst_.fn.vkResetFences(dev_, 1, &fence), "vkResetFences");
}

void VulkanBackend::abortFrameRecording() {
  // Something needs the results of the frame before endFrame(): run what was recorded
  // as ordinary work and do not replay it.
  if (!recordingFrame_) return;
  recordingFrame_ = false;
  frameValid_ = false;
  check(inst_.fn.vkEndCommandBuffer(frameCmd_), "vkEndCommandBuffer");
  submit(frameCmd_, frameFence_);
  frameInFlight_ = true;
}

void VulkanBackend::submit(VkCommandBuffer cb, VkFence fence) {
  auto si = vkStruct<VkSubmitInfo>(VK_STRUCTURE_TYPE_SUBMIT_INFO);
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cb;
  check(inst_.fn.vkQueueSubmit(queue_, 1, &si, fence), "vkQueueSubmit");
}

// Submits pending work and waits for everything in flight.
void VulkanBackend::flush() {
  ensureUsable();
  abortFrameRecording();
  if (immRecording_) {
    immRecording_ = false;
    check(inst_.fn.vkEndCommandBuffer(immCmd_), "vkEndCommandBuffer");
    submit(immCmd_, immFence_);
    immInFlight_ = true;
  }
  if (frameInFlight_) {
    frameInFlight_ = false;
    waitFence(frameFence_, "the frame");
  }
  if (immInFlight_) {
    immInFlight_ = false;
    waitFence(immFence_, "queued work");
    check(inst_.fn.vkResetCommandBuffer(immCmd_, 0), "vkResetCommandBuffer");
  }
}

void VulkanBackend::synchronize() { flush(); }

template <class PC>
void VulkanBackend::dispatch(Shader s, const PC& pc, int w, int h) {
  dispatchGroups(s, pc, (uint32_t(w) + kGroup - 1) / kGroup, (uint32_t(h) + kGroup - 1) / kGroup);
}

template <class PC>
void VulkanBackend::dispatchGroups(Shader s, const PC& pc, uint32_t groupsX, uint32_t groupsY) {
  static_assert(sizeof(PC) <= kPushBytes, "push constants exceed 128 bytes");
  VkPipeline p = pipeline(s);
  VkCommandBuffer cb = recorder();
  uint8_t bytes[kPushBytes] = {};
  std::memcpy(bytes, &pc, sizeof(PC));
  barrier(cb);
  inst_.fn.vkCmdBindPipeline(cb, VK_PIPELINE_BIND_POINT_COMPUTE, p);
  inst_.fn.vkCmdPushConstants(cb, layout_, VK_SHADER_STAGE_COMPUTE_BIT, 0, kPushBytes, bytes);
  inst_.fn.vkCmdDispatch(cb, groupsX, groupsY, 1);
}

void VulkanBackend::beginFrame() {
  flush();
  check(inst_.fn.vkResetCommandBuffer(frameCmd_, 0), "vkResetCommandBuffer");
  auto bi = vkStruct<VkCommandBufferBeginInfo>(VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO);
  check(inst_.fn.vkBeginCommandBuffer(frameCmd_, &bi), "vkBeginCommandBuffer");
  recordingFrame_ = true;
  frameValid_ = false;
  frameHasTimestamps_ = false;
}

void VulkanBackend::endFrame() {
  if (!recordingFrame_) return;  // aborted: already submitted
  recordingFrame_ = false;
  check(inst_.fn.vkEndCommandBuffer(frameCmd_), "vkEndCommandBuffer");
  submit(frameCmd_, frameFence_);
  frameInFlight_ = true;
  // A profiled frame holds timestamp writes (queries reset once per profiled frame): it
  // is run, not replayed.
  frameValid_ = !frameHasTimestamps_;
}

void VulkanBackend::replayFrame() {
  if (!frameValid_) throw Error("vulkan backend: no recorded frame to replay");
  flush();  // uploads are done; the previous frame has finished
  submit(frameCmd_, frameFence_);
  frameInFlight_ = true;
}

// ---- stage timing with timestamp queries ----

void VulkanBackend::beginStage(const std::string& name) {
  if (!queryPool_) {
    Backend::beginStage(name);
    return;
  }
  VkCommandBuffer cb = recorder();
  if (recordingFrame_) frameHasTimestamps_ = true;
  if (queryCount_ == 0) inst_.fn.vkCmdResetQueryPool(cb, queryPool_, 0, queryCapacity_);
  if (queryCount_ >= queryCapacity_) return;  // beyond capacity the rest of the batch goes to the last stage
  inst_.fn.vkCmdWriteTimestamp(cb, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, queryPool_, queryCount_++);
  stampNames_.push_back(name);
}

std::vector<StageTime> VulkanBackend::takeStageTimes() {
  if (!queryPool_) return Backend::takeStageTimes();
  std::vector<StageTime> out;
  if (queryCount_ == 0) return out;
  beginStage("");
  flush();
  std::vector<uint64_t> ticks(queryCount_);
  check(inst_.fn.vkGetQueryPoolResults(dev_, queryPool_, 0, queryCount_, ticks.size() * sizeof(uint64_t), ticks.data(),
                                       sizeof(uint64_t), VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT),
        "vkGetQueryPoolResults");
  const double msPerTick = double(props_.limits.timestampPeriod) * 1e-6;
  for (size_t i = 0; i + 1 < ticks.size(); ++i) {
    if (stampNames_[i].empty()) continue;
    const uint64_t a = ticks[i] & timestampMask_, b = ticks[i + 1] & timestampMask_;
    const double ms = double((b - a) & timestampMask_) * msPerTick;
    auto it = std::find_if(out.begin(), out.end(), [&](const StageTime& s) { return s.name == stampNames_[i]; });
    if (it == out.end())
      out.push_back({stampNames_[i], ms});
    else
      it->ms += ms;
  }
  queryCount_ = 0;
  stampNames_.clear();
  return out;
}

// ---- transfers ----

void VulkanBackend::doUpload(const Buffer& dst, const float* host) {
  const Alloc& a = alloc(dst);
  const VkDeviceSize bytes = dst.count() * sizeof(float);
  flush();  // the staging buffer is free and earlier work has finished
  if (staging_.size < bytes) {
    destroyBuffer(staging_);
    staging_ = makeBuffer(std::max<VkDeviceSize>(bytes, VkDeviceSize(4) << 20), true);
  }
  std::memcpy(staging_.mapped, host, bytes);
  VkCommandBuffer cb = recorder();
  barrier(cb);
  VkBufferCopy region{0, a.offset, bytes};
  inst_.fn.vkCmdCopyBuffer(cb, staging_.buffer, arenas_[size_t(a.arena)].buffer, 1, &region);
  flush();
}

void VulkanBackend::doDownload(const Buffer& src, float* host) {
  const Alloc& a = alloc(src);
  const VkDeviceSize bytes = src.count() * sizeof(float);
  flush();
  if (staging_.size < bytes) {
    destroyBuffer(staging_);
    staging_ = makeBuffer(std::max<VkDeviceSize>(bytes, VkDeviceSize(4) << 20), true);
  }
  VkCommandBuffer cb = recorder();
  barrier(cb);
  VkBufferCopy region{a.offset, 0, bytes};
  inst_.fn.vkCmdCopyBuffer(cb, arenas_[size_t(a.arena)].buffer, staging_.buffer, 1, &region);
  auto mb = vkStruct<VkMemoryBarrier>(VK_STRUCTURE_TYPE_MEMORY_BARRIER);
  mb.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  mb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
  inst_.fn.vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &mb, 0, nullptr,
                                0, nullptr);
  flush();
  std::memcpy(host, staging_.mapped, bytes);
}

void VulkanBackend::doFill(const Buffer& dst, float value) {
  const Alloc& a = alloc(dst);
  uint32_t bits;
  std::memcpy(&bits, &value, 4);
  VkCommandBuffer cb = recorder();
  barrier(cb);
  inst_.fn.vkCmdFillBuffer(cb, arenas_[size_t(a.arena)].buffer, a.offset, dst.count() * sizeof(float), bits);
}

void VulkanBackend::doCopy(const Buffer& dst, const Buffer& src) {
  const Alloc& d = alloc(dst);
  const Alloc& s = alloc(src);
  VkCommandBuffer cb = recorder();
  barrier(cb);
  VkBufferCopy region{s.offset, d.offset, src.count() * sizeof(float)};
  if (d.arena == s.arena && region.srcOffset == region.dstOffset) return;
  inst_.fn.vkCmdCopyBuffer(cb, arenas_[size_t(s.arena)].buffer, arenas_[size_t(d.arena)].buffer, 1, &region);
}

// Internal temporaries (the blurred image of the structure tensor), one per size and slot.
Buffer VulkanBackend::scratch(int slot, int w, int h) {
  auto key = std::make_tuple(slot, w, h);
  auto it = scratch_.find(key);
  if (it != scratch_.end()) return it->second;
  const bool wasValid = frameValid_;
  Buffer b = create(w, h, 1);
  frameValid_ = wasValid;
  scratch_[key] = b;
  return b;
}

// ---- kernels ----

// Backend has checked every kernel's arguments against its contract (backend.hpp).

void VulkanBackend::doFields(const Buffer& mask, const Buffer& calibration, const Buffer& trajectory,
                             const FieldsParams& p) {
  // The same quantities core/src/fields.cpp derives per pixel, derived once here.
  double tPrime[3];
  for (int i = 0; i < 3; ++i) tPrime[i] = p.R[0 * 3 + i] * p.t[0] + p.R[1 * 3 + i] * p.t[1] + p.R[2 * 3 + i] * p.t[2];
  const double tn = std::sqrt(tPrime[0] * tPrime[0] + tPrime[1] * tPrime[1] + tPrime[2] * tPrime[2]);
  constexpr double kDegToRad = M_PI / 180.0;
  auto setParams = [&](auto& prm) {
    using S = std::remove_reference_t<decltype(prm.R[0])>;
    prm.cam0 = toVkCam<S>(p.cam0);
    prm.cam1 = toVkCam<S>(p.cam1);
    for (int i = 0; i < 9; ++i) prm.R[i] = S(p.R[i]);
    for (int i = 0; i < 3; ++i) {
      prm.tPrime[i] = S(tPrime[i]);
      prm.tDir[i] = S(tn > 0 ? tPrime[i] / tn : tPrime[i]);
    }
    prm.halfFov = S(0.5 * p.maxFovDeg * kDegToRad);
    prm.epipole = S(p.epipoleDeg * kDegToRad);
    prm.useFov = p.maxFovDeg > 0 ? 1 : 0;
  };
  Addr block;
  if (float64_) {
    VkFieldsParams<double> prm{};
    setParams(prm);
    block = paramBlock(&prm, sizeof(prm));
  } else {
    VkFieldsParams<float> prm{};
    setParams(prm);
    block = paramBlock(&prm, sizeof(prm));
  }
  frameValid_ = false;  // a new pose: the recorded frame's triangulation is stale
  PcFields pc{addr(mask), addr(calibration), addr(trajectory), block, mask.width, mask.height};
  dispatch(float64_ ? kFields64 : kFields32, pc, mask.width, mask.height);
}

void VulkanBackend::doTriangulate(const Buffer& radial, const Buffer& points, const Buffer& w, const Buffer& mask,
                                  const CameraParams& cam0, const double tPrime[3]) {
  Addr block;
  if (float64_) {
    VkTriangulateParams<double> prm{};
    prm.cam0 = toVkCam<double>(cam0);
    for (int i = 0; i < 3; ++i) prm.tPrime[i] = tPrime[i];
    block = paramBlock(&prm, sizeof(prm));
  } else {
    VkTriangulateParams<float> prm{};
    prm.cam0 = toVkCam<float>(cam0);
    for (int i = 0; i < 3; ++i) prm.tPrime[i] = float(tPrime[i]);
    block = paramBlock(&prm, sizeof(prm));
  }
  PcTriangulate pc{addr(radial), addr(points), addr(w), addr(mask), block, radial.width, radial.height};
  dispatch(float64_ ? kTriangulate64 : kTriangulate32, pc, radial.width, radial.height);
}

void VulkanBackend::doWarp(const Buffer& dst, const Buffer& src, const Buffer& flow) {
  PcWarp pc{addr(dst), addr(src), addr(flow), dst.width, dst.height, dst.channels, src.width, src.height};
  dispatch(kWarp, pc, dst.width, dst.height);
}

void VulkanBackend::doDownsample(const Buffer& dst, const Buffer& src, float scale) {
  const float sigma = 0.5f * scale;  // resample.cpp decimationSigma
  const int radius = int(std::ceil(2.f * sigma));
  PcDownsample pc{addr(dst), addr(src),  dst.width, dst.height, dst.channels,
                  src.width, src.height, radius,    scale,      sigma};
  dispatch(kDownsample, pc, dst.width, dst.height);
}

void VulkanBackend::doUpsample(const Buffer& dst, const Buffer& src, float scale, float valueScale) {
  PcUpsample pc{addr(dst), addr(src), dst.width, dst.height, dst.channels, src.width, src.height, scale, valueScale};
  dispatch(kUpsample, pc, dst.width, dst.height);
}

// Two passes (normalise_moments.comp, normalise.comp); the taps by device address.
void VulkanBackend::doNormalise(const Buffer& dst, const Buffer& moments, const Buffer& src, const Buffer& mask,
                                const NormaliseParams& p) {
  const vk::NormaliseBlock block = vk::normaliseBlock(p);
  const Addr prm = paramBlock(&block, sizeof(block));
  const int w = src.width, h = src.height;
  dispatch(kNormaliseMoments, vk::PcNormaliseMoments{addr(moments), addr(src), addr(mask), prm, w, h}, w, h);
  dispatch(kNormalise, vk::PcNormalise{addr(dst), addr(moments), addr(src), addr(mask), prm, w, h}, w, h);
}

void VulkanBackend::doStructureTensor(const Buffer& tensor, const Buffer& steps, const Buffer& image,
                                      const Buffer& mask, const TensorParams& p) {
  const int w = image.width, h = image.height;
  Addr smooth = addr(image);
  if (p.sigma > 0.f) {
    const Buffer rows = scratch(0, w, h), blurred = scratch(1, w, h);
    const int radius = int(std::ceil(3.f * p.sigma));
    dispatch(kTensorBlur, PcBlur{addr(rows), addr(image), w, h, radius, 0, p.sigma}, w, h);
    dispatch(kTensorBlur, PcBlur{addr(blurred), addr(rows), w, h, radius, 1, p.sigma}, w, h);
    smooth = addr(blurred);
  }
  dispatch(kTensor, PcTensor{addr(tensor), smooth, w, h, p.beta, p.eta, p.wMin}, w, h);
  dispatch(kTensorSteps, PcSteps{addr(steps), addr(tensor), addr(mask), w, h, p.alpha0, p.alpha1}, w, h);
}

void VulkanBackend::doWarpDerivatives(const DataTermBuffers& data, const Buffer& tangent, const Buffer& i0,
                                      const Buffer& i1, const Buffer& trajectory, const Buffer& w, const Buffer& u,
                                      const Buffer& mask, const Buffer& confidence, float weightFloor) {
  const bool weighted = confidence.id >= 0;
  PcWarpDerivatives pc{addr(data.u0),
                       addr(data.iu),
                       addr(data.iz),
                       addr(tangent),
                       addr(i0),
                       addr(i1),
                       addr(trajectory),
                       addr(w),
                       addr(u),
                       addr(mask),
                       weighted ? addr(confidence) : addr(mask),
                       mask.width,
                       mask.height,
                       weighted ? 1 : 0,
                       weightFloor};
  dispatch(kWarpDerivatives, pc, mask.width, mask.height);
}

void VulkanBackend::doPrimalDual(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor,
                                 const Buffer& steps, const Buffer& mask, const PrimalDualParams& prm) {
  const int w = mask.width, h = mask.height;
  for (const PrimalDualStep& step : prm.schedule) {
    PcDual dual{addr(pd.uBar),   addr(pd.vBar), addr(pd.p), addr(pd.q), addr(tensor), addr(steps), addr(mask), w, h,
                step.sigmaScale, prm.alpha0,    prm.alpha1};
    dispatch(kDual, dual, w, h);
    PcPrimal primal{addr(pd.u),    addr(pd.uBar), addr(pd.v),   addr(pd.vBar), addr(pd.p), addr(pd.q), addr(data.u0),
                    addr(data.iu), addr(data.iz), addr(tensor), addr(steps),   addr(mask), w,          h,
                    step.tauScale, step.theta,    prm.lambda,   prm.alpha0,    prm.alpha1};
    dispatch(kPrimal, primal, w, h);
  }
}

void VulkanBackend::doMedian(const Buffer& dst, const Buffer& src, const Buffer& mask) {
  dispatch(kMedian, PcMedian{addr(dst), addr(src), addr(mask), mask.width, mask.height}, mask.width, mask.height);
}

void VulkanBackend::doAccumulate(const Buffer& u, const Buffer& w, const Buffer& u0, const Buffer& tangent,
                                 const Buffer& mask, float duMax) {
  PcAccumulate pc{addr(u), addr(w), addr(u0), addr(tangent), addr(mask), mask.width, mask.height, duMax};
  dispatch(kAccumulate, pc, mask.width, mask.height);
}

// ---- plane sweep ----

// Mirrors kMaxPlanes in sweep_aggregate.comp (the path costs of two steps in shared memory).
static_assert(kMaxSweepPlanes <= 1024, "sweep_aggregate.comp holds at most 1024 planes");

// The camera, translation and nearest sphere, in the precision of the geometry shaders.
Addr VulkanBackend::sweepParamBlock(const SweepParams& p) {
  auto store = [&](auto prm) {
    using S = std::remove_reference_t<decltype(prm.qMax)>;
    prm.cam = toVkCam<S>(p.cam);
    for (int i = 0; i < 3; ++i) prm.t[i] = S(p.t[i]);
    prm.qMax = S(p.qMax);
    return paramBlock(&prm, sizeof(prm));
  };
  return float64_ ? store(VkSweepParams<double>{}) : store(VkSweepParams<float>{});
}

void VulkanBackend::doSweepWarp(const Buffer& volume, const Buffer& image, const Buffer& mask, const SweepParams& p) {
  PcSweepWarp pc{addr(volume), addr(image), addr(mask), sweepParamBlock(p), volume.width, volume.height, p.planes};
  dispatch(float64_ ? kSweepWarp64 : kSweepWarp32, pc, volume.width, volume.height);
}

void VulkanBackend::doSweepCost(const Buffer& costs, const Buffer& reference, const Buffer& volume, const Buffer& mask,
                                const SweepParams& p) {
  // One invocation per (pixel, plane), a row's (x * planes + k) in runs of kGroup^2: the
  // interleaved volume is read and the costs written in consecutive floats.
  const uint64_t rowItems = uint64_t(costs.width) * uint64_t(p.planes);
  const uint64_t groupItems = uint64_t(kGroup) * kGroup;
  PcSweepCost pc{addr(costs),  addr(reference), addr(volume), addr(mask),    costs.width,
                 costs.height, p.planes,        p.radius,     p.flatVariance};
  dispatchGroups(kSweepCost, pc, uint32_t((rowItems + groupItems - 1) / groupItems), uint32_t(costs.height));
}

void VulkanBackend::doSweepAggregate(const Buffer& aggregated, const Buffer& costs, const Buffer& mask,
                                     const SweepParams& p) {
  // +x, -x, +y, -y in the oracle's order, one work group per scanline (rows for x, columns
  // for y). The first direction writes every pixel, the others add: no fill needed.
  // dispatchGroups puts a full barrier before each dispatch.
  const int w = aggregated.width, h = aggregated.height;
  for (int direction = 0; direction < 4; ++direction) {
    PcSweepAggregate pc{addr(aggregated), addr(costs), addr(mask), w, h, p.planes, direction, p.p1, p.p2};
    dispatchGroups(kSweepAggregate, pc, uint32_t(direction < 2 ? h : w), 1);
  }
}

void VulkanBackend::doSweepSelect(const Buffer& best, const Buffer& aggregated, const Buffer& costs, const Buffer& mask,
                                  const SweepParams& p) {
  // The plane index becomes an inverse depth in the geometry shaders' precision (double as
  // the oracle where the device has shaderFloat64).
  PcSweepSelect pc{addr(best),         addr(aggregated), addr(costs), addr(mask),
                   sweepParamBlock(p), best.width,       best.height, p.planes};
  dispatch(float64_ ? kSweepSelect64 : kSweepSelect32, pc, best.width, best.height);
}

void VulkanBackend::doSweepInitialise(const Buffer& u, const Buffer& w, const Buffer& confidence, const Buffer& best,
                                      const Buffer& other, const Buffer& mask, const SweepParams& p,
                                      const ConsistencyParams& c) {
  // Two dispatches of one shader (dispatch puts a full barrier before each): pass 0 writes
  // the confidence and the consistent pixels' warp, pass 1 reads that confidence to fill
  // occluded pixels from the surface ahead of them.
  const Shader shader = float64_ ? kSweepInitialise64 : kSweepInitialise32;
  const Addr params = sweepParamBlock(p);
  for (int32_t pass = 0; pass < 2; ++pass) {
    PcSweepInitialise pc{addr(u), addr(w),  addr(confidence), addr(best),         addr(other), addr(mask), params,
                         u.width, u.height, c.tolerancePx,    c.acceptConfidence, pass,        p.planes};
    dispatch(shader, pc, u.width, u.height);
  }
}

}  // namespace

std::string probeVulkan(const std::string& device) { return probe(device, false); }
std::string probeVulkanAuto(const std::string& device) { return probe(device, true); }

std::unique_ptr<Backend> createVulkanBackend(const std::string& device) {
  return std::make_unique<VulkanBackend>(device);
}

long long vulkanValidationMessageCount() { return gValidationCount.load(); }
std::string vulkanValidationLastMessage() {
  std::lock_guard<std::mutex> lock(gValidationMutex);
  return gLastValidationMessage;
}
bool vulkanValidationLayerActive() { return gLayerActive.load(); }

}  // namespace cs
