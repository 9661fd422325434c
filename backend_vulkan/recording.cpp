// The Vulkan backend's command recording: pipelines (one per shader, made on first use),
// the immediate command buffer and the recorded frame, submission and fences, replay, and
// stage times from timestamp queries.
#include <algorithm>
#include <chrono>

#include "curvestereo/image.hpp"
#include "shader_table.hpp"
#include "vulkan_impl.hpp"

namespace cs::vk {

VkPipeline VulkanBackend::pipeline(Shader s) {
  if (pipelines_[s]) return pipelines_[s];
  const EmbeddedShader* found = &embeddedShaders().at(size_t(s));
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
  if (recordingFrame()) return frameCmd();
  if (imm_ == Immediate::InFlight) {  // submitted by replayFrame: done before it is recorded again
    imm_ = Immediate::Idle;
    waitFence(immFence_, "queued work");
    check(inst_.fn.vkResetCommandBuffer(immCmd_, 0), "vkResetCommandBuffer");
  }
  if (imm_ != Immediate::Recording) {
    lastImm_ = Cmd::None;
    auto bi = vkStruct<VkCommandBufferBeginInfo>(VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO);
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    check(inst_.fn.vkBeginCommandBuffer(immCmd_, &bi), "vkBeginCommandBuffer");
    imm_ = Immediate::Recording;
  }
  return immCmd_;
}

// Every command depends on everything before it (kernels read what the previous ones
// wrote; transfers and dispatches interleave): a memory barrier between them. The first
// command of a command buffer waits for everything submitted before (host writes,
// transfers, dispatches); later ones only for the kind of command before them in the same
// buffer (the first barrier already ordered everything earlier), compute after compute
// alone in the usual case.
void VulkanBackend::barrier(VkCommandBuffer cb, Cmd next) {
  Cmd& last = cb == immCmd_ ? lastImm_ : lastFrame_;
  auto mb = vkStruct<VkMemoryBarrier>(VK_STRUCTURE_TYPE_MEMORY_BARRIER);
  VkPipelineStageFlags src = 0, dst = 0;
  if (last == Cmd::None || last == Cmd::Transfer) {
    src |= VK_PIPELINE_STAGE_TRANSFER_BIT;
    mb.srcAccessMask |= VK_ACCESS_TRANSFER_WRITE_BIT;
  }
  if (last == Cmd::None || last == Cmd::Dispatch) {
    src |= VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
    mb.srcAccessMask |= VK_ACCESS_SHADER_WRITE_BIT;
  }
  if (last == Cmd::None) {
    src |= VK_PIPELINE_STAGE_HOST_BIT;
    mb.srcAccessMask |= VK_ACCESS_HOST_WRITE_BIT;
  }
  if (next == Cmd::Dispatch) {
    dst = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
    mb.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
  } else {
    dst = VK_PIPELINE_STAGE_TRANSFER_BIT;
    mb.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
  }
  inst_.fn.vkCmdPipelineBarrier(cb, src, dst, 0, 1, &mb, 0, nullptr, 0, nullptr);
  last = next;
}

// Polled for up to spinNs_ first, as CUDA's default synchronisation spins: a blocking
// vkWaitForFences sleeps in the driver, and its wake-up adds to every frame. Past that (at
// once on a CPU device), the blocking wait, whose timeout marks the device hung.
void VulkanBackend::waitFence(VkFence fence, const char* what) {
  const bool done = spinUntil(std::chrono::steady_clock::now(), spinNs_, [&] {
    const VkResult s = inst_.fn.vkGetFenceStatus(dev_, fence);
    if (s != VK_SUCCESS && s != VK_NOT_READY) check(s, what);
    return s == VK_SUCCESS;
  });
  VkResult r = done ? VK_SUCCESS : inst_.fn.vkWaitForFences(dev_, 1, &fence, VK_TRUE, timeoutNs_);
  if (r == VK_TIMEOUT) {
    health_ = Health::Hung;
    throw Error(std::string("vulkan backend: ") + what + " did not finish within " +
                std::to_string(timeoutNs_ / 1000000000ull) + " s (device hung?)");
  }
  check(r, what);
  check(inst_.fn.vkResetFences(dev_, 1, &fence), "vkResetFences");
}

void VulkanBackend::abortFrameRecording() {
  // Something needs the results of the frame before endFrame(): run what was recorded
  // as ordinary work and do not replay it.
  if (!recordingFrame()) return;
  FrameSlot& f = frames_[recordingSlot_];
  recordingSlot_ = -1;
  f.state = Frame::Empty;  // until submitted
  check(inst_.fn.vkEndCommandBuffer(f.cmd), "vkEndCommandBuffer");
  submit(f.cmd, f.fence);
  f.state = Frame::RunningOnce;
}

void VulkanBackend::submit(VkCommandBuffer cb, VkFence fence) {
  auto si = vkStruct<VkSubmitInfo>(VK_STRUCTURE_TYPE_SUBMIT_INFO);
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cb;
  std::lock_guard<std::mutex> lock(*queueLock_);
  check(inst_.fn.vkQueueSubmit(queue_, 1, &si, fence), "vkQueueSubmit");
}

// The immediate command buffer, when it holds commands, ended and submitted without a
// wait (flush or recorder() waits for its fence before it is recorded again).
void VulkanBackend::submitImmediate() {
  if (imm_ != Immediate::Recording) return;
  imm_ = Immediate::Idle;
  check(inst_.fn.vkEndCommandBuffer(immCmd_), "vkEndCommandBuffer");
  submit(immCmd_, immFence_);
  imm_ = Immediate::InFlight;
}

// Submits pending work and waits for everything in flight.
void VulkanBackend::flush() {
  ensureUsable();
  abortFrameRecording();
  submitImmediate();
  for (FrameSlot& f : frames_) {
    if (f.state != Frame::Running && f.state != Frame::RunningOnce) continue;
    f.state = f.state == Frame::Running ? Frame::Ready : Frame::Empty;
    waitFence(f.fence, "the frame");
  }
  if (imm_ == Immediate::InFlight) {
    imm_ = Immediate::Idle;
    waitFence(immFence_, "queued work");
    check(inst_.fn.vkResetCommandBuffer(immCmd_, 0), "vkResetCommandBuffer");
  }
  stagingUsed_ = 0;  // every upload's copy has run
}

void VulkanBackend::synchronize() { flush(); }

// Every slot's command buffer starts with a full barrier (the first command's, lastFrame_
// None): it waits on the device for everything submitted before it to the one queue, the
// other slots' frames and the immediate work alike. On the host, a slot is resubmitted only
// after its own previous submission finished (its fence); beginFrame waits for all.
void VulkanBackend::beginFrame(int slot) {
  if (slot < 0 || slot >= kFrameSlots)
    throw Error("vulkan backend: frame slot " + std::to_string(slot) + " is not in 0.." +
                std::to_string(kFrameSlots - 1));
  // A profiled frame's uploads end here: the host's recording of the frame, which a
  // replayed frame does not do, is no stage's time.
  if (queryCount_ > 0 && imm_ == Immediate::Recording) beginStage("");
  flush();  // no slot in flight: the slot's command buffer may be reset
  FrameSlot& f = frames_[slot];
  f.state = Frame::Empty;
  check(inst_.fn.vkResetCommandBuffer(f.cmd, 0), "vkResetCommandBuffer");
  auto bi = vkStruct<VkCommandBufferBeginInfo>(VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO);
  check(inst_.fn.vkBeginCommandBuffer(f.cmd, &bi), "vkBeginCommandBuffer");
  lastFrame_ = Cmd::None;
  f.state = Frame::Recording;
  recordingSlot_ = slot;
}

void VulkanBackend::endFrame() {
  if (!recordingFrame()) return;  // aborted: already submitted
  FrameSlot& f = frames_[recordingSlot_];
  recordingSlot_ = -1;
  // A profiled frame holds timestamp writes (queries reset once per profiled frame): it
  // is run, not replayed.
  const bool timed = f.state == Frame::RecordingTimed;
  f.state = Frame::Empty;  // until submitted
  check(inst_.fn.vkEndCommandBuffer(f.cmd), "vkEndCommandBuffer");
  submit(f.cmd, f.fence);
  f.state = timed ? Frame::RunningOnce : Frame::Running;
}

void VulkanBackend::replayFrame(int slot) {
  if (!canReplayFrame(slot))
    throw Error("vulkan backend: no recorded frame in slot " + std::to_string(slot) + " to replay");
  ensureUsable();
  abortFrameRecording();  // another slot's frame being recorded runs first, once
  FrameSlot& f = frames_[slot];
  // The slot's previous run has finished before its command buffer is submitted again
  // (other slots still in flight need no wait: queue order and the barrier at the start of
  // the command buffer keep this frame behind them on the device).
  if (f.state == Frame::Running) {
    f.state = Frame::Ready;
    waitFence(f.fence, "the frame");
  }
  // The work issued since (uploads, fills, copies: the sequence's state and motion) goes
  // first and is not waited for: queue order and the barrier before the frame's first
  // command keep the frame behind it (a download's flush waits for both).
  submitImmediate();
  submit(f.cmd, f.fence);
  f.state = Frame::Running;
}

// ---- stage timing with timestamp queries ----

void VulkanBackend::beginStage(const std::string& name) {
  if (!queryPool_) {
    Backend::beginStage(name);
    return;
  }
  VkCommandBuffer cb = recorder();
  if (recordingFrame() && frames_[recordingSlot_].state == Frame::Recording)
    frames_[recordingSlot_].state = Frame::RecordingTimed;
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

}  // namespace cs::vk
