// The Vulkan backend's device layer: the loader (opened at run time with dlopen, so a build
// with Vulkan runs on machines without it: the backend then reports "no Vulkan loader" and
// auto falls back), the function tables, the instance (with the validation layer on
// request) and the choice of device.
#pragma once
#define VK_NO_PROTOTYPES
#include <vulkan/vulkan.h>

#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace cs::vk {

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
  X(vkEnumerateDeviceExtensionProperties)     \
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
  X(vkCmdUpdateBuffer)                        \
  X(vkCmdWriteTimestamp)                      \
  X(vkCmdResetQueryPool)                      \
  X(vkCreateQueryPool)                        \
  X(vkDestroyQueryPool)                       \
  X(vkGetQueryPoolResults)                    \
  X(vkCreateFence)                            \
  X(vkDestroyFence)                           \
  X(vkWaitForFences)                          \
  X(vkGetFenceStatus)                         \
  X(vkCreateEvent)                            \
  X(vkDestroyEvent)                           \
  X(vkGetEventStatus)                         \
  X(vkResetEvent)                             \
  X(vkCmdSetEvent)                            \
  X(vkResetFences)                            \
  X(vkQueueSubmit)                            \
  X(vkQueueWaitIdle)                          \
  X(vkDeviceWaitIdle)

#define CS_VK_DECLARE(name) PFN_##name name = nullptr;

struct Loader {
  void* lib = nullptr;
  PFN_vkGetInstanceProcAddr getInstanceProcAddr = nullptr;
  CS_VK_GLOBAL_FNS(CS_VK_DECLARE)
  std::string error;
};

// The process-wide loader, opened once.
const Loader& loader();

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

std::string resultText(VkResult r);

// CURVESTEREO_VULKAN_VALIDATION is set (and not "0").
bool validationRequested();

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
  std::string create(bool validation);
};

const char* typeName(VkPhysicalDeviceType t);

struct Candidate {
  VkPhysicalDevice device = VK_NULL_HANDLE;
  VkPhysicalDeviceProperties props{};
  // Every queue family that computes (none: unusable). The device gets one queue of each,
  // dealt to its backends in turn (sharedDevice).
  std::vector<uint32_t> computeFamilies;
  bool float64 = false, int64 = false;
  bool atomicFloatAdd = false;  // VK_EXT_shader_atomic_float's shaderBufferFloat32AtomicAdd
  std::string unusable;         // why this device cannot run the backend ("" if it can)
};

std::vector<Candidate> candidates(const Instance& inst);
// The device `spec` selects, or an error. autoMode: refuse devices that are not GPUs.
const Candidate* selectDevice(const std::vector<Candidate>& all, const std::string& spec, bool autoMode,
                              std::string& why);
// "" when a device matching `device` can be used, else why not (cached per process).
std::string probe(const std::string& device, bool autoMode);

// ---------------------------------------------------------------------------------------
// One instance, and one logical device per physical device, for the whole process.
//
// Every backend on a GPU shares its VkDevice, one context per GPU as CUDA has: a rig's
// directions pay a device's start-up once, and can come to share memory (a camera's image,
// which each of its directions uploads today). A backend takes a queue of its own while the
// family has one left, then shares one round-robin (lavapipe has a single queue); a queue's
// submissions and waits hold its lock (Vulkan asks the host to synchronise a queue's use).
// Measured on an H200 (2026-11-27, rig4_urban_dev): eight directions on eight queues of one
// device took as long as on eight devices (solves 39-40 against 42 ms): the driver ran them
// one after another either way, where CUDA's streams overlap them (20 ms).

// The process's instance, made with the validation layer when validationRequested();
// alive while a backend holds it. Throws cs::Error.
std::shared_ptr<Instance> sharedInstance();

struct SharedDevice {
  std::shared_ptr<Instance> instance;  // outlives the device
  VkDevice device = VK_NULL_HANDLE;
  struct Queue {
    VkQueue queue = VK_NULL_HANDLE;
    uint32_t family = 0;
    std::mutex lock;
  };
  // The first queue of every family that computes, taken in turn by the backends, so that
  // consecutive backends use other families; backends beyond them share (each queue's
  // submissions under its lock).
  std::vector<std::unique_ptr<Queue>> queues;
  bool atomicFloatAdd = false;  // enabled at creation (Candidate::atomicFloatAdd)
  bool abandoned = false;       // set by a backend that saw the device hang: never destroyed (leaked)
  unsigned queuesTaken = 0;

  SharedDevice() = default;
  SharedDevice(const SharedDevice&) = delete;
  SharedDevice& operator=(const SharedDevice&) = delete;
  ~SharedDevice();
};

// The logical device of candidate c (made on first use, with one queue of each compute family and
// the features the backend enables), and the queue this caller is to use.
// Throws cs::Error.
std::shared_ptr<SharedDevice> sharedDevice(const std::shared_ptr<Instance>& instance, const Candidate& c,
                                           SharedDevice::Queue*& queue);
// How many logical devices are alive in the process (the tests' view of the sharing).
int sharedDevicesAlive();

}  // namespace cs::vk
