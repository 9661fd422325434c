// The Vulkan backend (see vulkan_backend.hpp): the logical device, its queue, command
// pool, pipeline layout and timestamp queries. The other concerns have their own sources
// (vulkan_impl.hpp lists them).
#include "vulkan_backend.hpp"

#include <algorithm>
#include <cstdlib>

#include "curvestereo/image.hpp"
#include "vulkan_impl.hpp"

namespace cs {
namespace vk {

void VulkanBackend::check(VkResult r, const char* what) {
  if (r == VK_SUCCESS) return;
  if (r == VK_ERROR_DEVICE_LOST && health_ == Health::Ok) health_ = Health::Lost;
  throw Error(std::string("vulkan backend: ") + what + " failed: " + resultText(r));
}

void VulkanBackend::ensureUsable() const {
  if (health_ == Health::Hung)
    throw Error("vulkan backend: the device stopped responding earlier; create a new backend");
  if (health_ == Health::Lost) throw Error("vulkan backend: the device was lost earlier; create a new backend");
}

VulkanBackend::VulkanBackend(const std::string& spec) : instance_(sharedInstance()), inst_(*instance_) {
  std::string why;
  const std::vector<Candidate> all = candidates(inst_);
  const Candidate* c = selectDevice(all, spec, false, why);
  if (!c) throw Error("vulkan backend: " + why);
  phys_ = c->device;
  props_ = c->props;
  // The camera models run in float unless CURVESTEREO_VULKAN_DOUBLE_MODELS asks for double
  // (where the device has shaderFloat64: the oracle's precision, for the tests). GLSL has no
  // double sin, cos or atan, so real.glsl writes them out as long polynomials: in double the
  // geometry shaders (sweep warps and checks, carry, triangulation, the temporal filter) took
  // 3 to 4 times as long even on an H200's full-rate float64 (a warm frame 4.07 against
  // 3.28 ms), and a consumer GPU's float64 runs at 1/32 to 1/64 of its float rate. Float
  // rays are good to ~1e-4 px at 848x800, three orders below the solver's accuracy.
  const char* doubleModels = std::getenv("CURVESTEREO_VULKAN_DOUBLE_MODELS");
  deviceFloat64_ = c->float64;
  float64_ = c->float64 && doubleModels && *doubleModels && std::string(doubleModels) != "0";
  // primal_dual.comp's tile: the largest of 32 x 32, 32 x 16 and 16 x 16 cells whose
  // invocations and kPrimalDualCellBytes a cell of shared memory the device holds
  // (CURVESTEREO_VULKAN_SHARED_MEMORY lowers the device's limit, as on a device with less,
  // for tests of the smaller tiles).
  uint32_t shared = props_.limits.maxComputeSharedMemorySize;
  if (const char* m = std::getenv("CURVESTEREO_VULKAN_SHARED_MEMORY"))
    shared = std::min<uint32_t>(shared, uint32_t(std::max(0L, std::atol(m))));
  auto holds = [&](uint32_t w, uint32_t h) {
    return shared >= w * h * kPrimalDualCellBytes && props_.limits.maxComputeWorkGroupInvocations >= w * h &&
           props_.limits.maxComputeWorkGroupSize[0] >= w && props_.limits.maxComputeWorkGroupSize[1] >= h;
  };
  pdTile_ = holds(32, 32) ? PdTile::Square : holds(32, 16) ? PdTile::Wide : PdTile::Narrow;
  // The host polls for the device's work (fences, downloads' pieces: up to 20 ms, more
  // than a cold frame, then it blocks) rather than sleeping in the driver at once, whose
  // wake-up adds to a GPU frame; not on a CPU device, where polling takes a core from the
  // work itself.
  spinNs_ = props_.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU ? 0 : 20ull * 1000 * 1000;
  if (const char* s = std::getenv("CURVESTEREO_VULKAN_SPIN_US")) spinNs_ = uint64_t(std::max(0L, std::atol(s))) * 1000;
  if (const char* t = std::getenv("CURVESTEREO_VULKAN_TIMEOUT_S"))
    timeoutNs_ = uint64_t(std::max(1.0, std::atof(t)) * 1e9);
  inst_.fn.vkGetPhysicalDeviceMemoryProperties(phys_, &memProps_);

  auto driver = vkStruct<VkPhysicalDeviceDriverProperties>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES);
  auto subgroup = vkStruct<VkPhysicalDeviceSubgroupProperties>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES);
  driver.pNext = &subgroup;
  auto p2 = vkStruct<VkPhysicalDeviceProperties2>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2);
  p2.pNext = &driver;
  inst_.fn.vkGetPhysicalDeviceProperties2(phys_, &p2);
  // Subgroup arithmetic and shuffles in compute shaders (Vulkan 1.1 core;
  // CURVESTEREO_VULKAN_SUBGROUPS=0 turns them off, as on a device without them, for tests of
  // the fallback).
  const char* useSubgroups = std::getenv("CURVESTEREO_VULKAN_SUBGROUPS");
  auto subgroupsHave = [&](VkSubgroupFeatureFlags needed) {
    return props_.apiVersion >= VK_API_VERSION_1_1 && (subgroup.supportedStages & VK_SHADER_STAGE_COMPUTE_BIT) &&
           (subgroup.supportedOperations & needed) == needed && subgroup.subgroupSize >= 1 &&
           !(useSubgroups && std::string(useSubgroups) == "0");
  };
  subgroupArithmetic_ = subgroupsHave(VK_SUBGROUP_FEATURE_BASIC_BIT | VK_SUBGROUP_FEATURE_ARITHMETIC_BIT |
                                      VK_SUBGROUP_FEATURE_SHUFFLE_BIT);
  // Subgroup ballots (and their broadcasts), for panorama_splat.comp's shared large
  // footprints; off with the rest under CURVESTEREO_VULKAN_SUBGROUPS=0.
  subgroupBallot_ = subgroupsHave(VK_SUBGROUP_FEATURE_BASIC_BIT | VK_SUBGROUP_FEATURE_BALLOT_BIT);
  subgroupSize_ = subgroup.subgroupSize;
  description_ = std::string(props_.deviceName) + " (" + typeName(props_.deviceType) + ", Vulkan " +
                 std::to_string(VK_API_VERSION_MAJOR(props_.apiVersion)) + "." +
                 std::to_string(VK_API_VERSION_MINOR(props_.apiVersion)) + "." +
                 std::to_string(VK_API_VERSION_PATCH(props_.apiVersion)) + ", " + driver.driverName + " " +
                 driver.driverInfo + (float64_ ? ", camera models in double" : ", camera models in float") + ")";

  SharedDevice::Queue* queue = nullptr;
  device_ = sharedDevice(instance_, *c, queue);
  dev_ = device_->device;
  atomicFloatAdd_ = device_->atomicFloatAdd;  // what the device was made with, by whichever backend
  queue_ = queue->queue;
  queueLock_ = &queue->lock;
  queueFamily_ = queue->family;

  auto pci = vkStruct<VkCommandPoolCreateInfo>(VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO);
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = queueFamily_;
  check(inst_.fn.vkCreateCommandPool(dev_, &pci, nullptr, &pool_), "vkCreateCommandPool");
  auto cai = vkStruct<VkCommandBufferAllocateInfo>(VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO);
  cai.commandPool = pool_;
  cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  cai.commandBufferCount = 1;
  check(inst_.fn.vkAllocateCommandBuffers(dev_, &cai, &immCmd_), "vkAllocateCommandBuffers");
  auto fci = vkStruct<VkFenceCreateInfo>(VK_STRUCTURE_TYPE_FENCE_CREATE_INFO);
  check(inst_.fn.vkCreateFence(dev_, &fci, nullptr, &immFence_), "vkCreateFence");
  for (FrameSlot& f : frames_) {  // one recorded frame per slot (beginFrame)
    check(inst_.fn.vkAllocateCommandBuffers(dev_, &cai, &f.cmd), "vkAllocateCommandBuffers");
    check(inst_.fn.vkCreateFence(dev_, &fci, nullptr, &f.fence), "vkCreateFence");
  }

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

  params_ = makeBuffer(1 << 20, Memory::Params);
  fillByteTable();
}

VulkanBackend::~VulkanBackend() {
  if (!dev_) return;
  if (health_ == Health::Hung) {  // work may still run on the device: leak rather than free memory in use
    device_->abandoned = true;
    return;
  }
  {
    std::lock_guard<std::mutex> lock(*queueLock_);
    inst_.fn.vkQueueWaitIdle(queue_);
  }
  for (VkPipeline p : pipelines_)
    if (p) inst_.fn.vkDestroyPipeline(dev_, p, nullptr);
  for (Arena& a : arenas_) destroyBuffer(a);
  destroyBuffer(staging_);
  destroyBuffer(stagingMirror_);
  destroyBuffer(lut_);
  destroyBuffer(params_);
  if (queryPool_) inst_.fn.vkDestroyQueryPool(dev_, queryPool_, nullptr);
  if (layout_) inst_.fn.vkDestroyPipelineLayout(dev_, layout_, nullptr);
  if (immFence_) inst_.fn.vkDestroyFence(dev_, immFence_, nullptr);
  for (VkEvent e : pieceEvents_) inst_.fn.vkDestroyEvent(dev_, e, nullptr);
  for (FrameSlot& f : frames_)
    if (f.fence) inst_.fn.vkDestroyFence(dev_, f.fence, nullptr);
  if (pool_) inst_.fn.vkDestroyCommandPool(dev_, pool_, nullptr);
}

}  // namespace vk

std::unique_ptr<Backend> createVulkanBackend(const std::string& device) {
  return std::make_unique<vk::VulkanBackend>(device);
}

}  // namespace cs
