// The Vulkan backend: every kernel of cs::Backend as a GLSL compute shader (../shaders),
// run on any conformant Vulkan 1.2 device with bufferDeviceAddress (Mesa lavapipe in CI,
// NVIDIA/AMD/Intel GPUs). Buffers live in device-local arenas and are reached by device
// address from push constants; each kind of frame (a slot of beginFrame: cold or warm,
// filtered or not) is recorded once into a command buffer of its own and resubmitted;
// per-stage times come from timestamp queries.
//
// Device selection ("--device"): "" picks the best device (discrete > integrated >
// virtual > CPU), a number the device of that index, anything else the first device
// whose name contains it (case-insensitive).
//
// Validation: with CURVESTEREO_VULKAN_VALIDATION=1 in the environment, instances enable
// VK_LAYER_KHRONOS_validation (when installed) and count its warnings and errors.
//
// Waiting: the host polls fences and downloads' pieces for up to CURVESTEREO_VULKAN_SPIN_US
// microseconds (default 20000; 0 on a CPU device such as lavapipe) before it blocks in the
// driver, as CUDA's default synchronisation spins; 0 blocks at once.
#pragma once
#include <memory>
#include <string>

#include "curvestereo/backend.hpp"

namespace cs {

// "" when a Vulkan device matching `device` can be used, else why not.
std::string probeVulkan(const std::string& device);
// As probeVulkan, for "--backend auto": with no device selector, a device that is not a
// real GPU (lavapipe/llvmpipe and other CPU implementations) is refused, so that auto
// falls back to the CPU oracle rather than an emulated GPU.
std::string probeVulkanAuto(const std::string& device);
std::unique_ptr<Backend> createVulkanBackend(const std::string& device);

// Validation-layer messages (warnings and errors) seen by this process, and whether the
// layer was available when the last Vulkan instance was created with validation asked for.
long long vulkanValidationMessageCount();
// Vulkan logical devices alive in this process: one per GPU in use, shared by its backends.
int vulkanDevicesAlive();
std::string vulkanValidationLastMessage();
bool vulkanValidationLayerActive();

}  // namespace cs
