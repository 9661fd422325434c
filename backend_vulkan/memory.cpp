// The Vulkan backend's memory: device-local arenas that buffers sit in back to back,
// host-visible parameter blocks, the staging buffer of transfers, and the transfers.
#include <algorithm>
#include <chrono>
#include <cstring>

#include "curvestereo/image.hpp"
#include "curvestereo/parallel.hpp"
#include "vulkan_impl.hpp"

namespace cs::vk {

namespace {
// bytes_to_floats.comp's push constants.
struct PcBytesToFloats {
  Addr dst, src, table;
  uint32_t n;
};

// Where parameter blocks and staged regions start: on 256 bytes, one rule for both and
// for the downloads' layout and the staging claims that must agree on it.
VkDeviceSize aligned256(VkDeviceSize bytes) { return (bytes + 255) & ~VkDeviceSize(255); }
}  // namespace

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

VulkanBackend::Arena VulkanBackend::makeBuffer(VkDeviceSize bytes, Memory kind) {
  const bool hostVisible = kind != Memory::Device;
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
  const VkMemoryPropertyFlags host = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  mai.memoryTypeIndex = kind == Memory::Device ? memoryType(req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0)
                        : kind == Memory::Staging
                            ? memoryType(req.memoryTypeBits, host, VK_MEMORY_PROPERTY_HOST_CACHED_BIT)
                            : memoryType(req.memoryTypeBits, host, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
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
    arenas_.push_back(makeBuffer(std::max<VkDeviceSize>(VkDeviceSize(64) << 20, aligned), Memory::Device));
  Arena& a = arenas_.back();
  allocs_.push_back({int(arenas_.size() - 1), a.used, bytes});
  a.used += aligned;
  invalidateFrame();  // a new pipeline (new buffers) must not replay an old frame
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
  const VkDeviceSize aligned = aligned256(bytes);
  if (paramsUsed_ + aligned > params_.size) {
    // Full (thousands of poses): wait until no submitted work reads a block, then start over.
    flush();
    paramCache_.clear();
    paramsUsed_ = 0;
    invalidateFrame();
  }
  std::memcpy(static_cast<char*>(params_.mapped) + paramsUsed_, data, bytes);
  paramCache_[key] = paramsUsed_;
  const Addr a = params_.address + paramsUsed_;
  paramsUsed_ += aligned;
  return a;
}

// ---- transfers ----

// Room for `bytes` in the persistently mapped staging buffer, after what the immediate
// command buffer's copies already use: their offset (256-aligned). Where the room is not
// there, or a frame is being recorded, the queued work runs first and the buffer starts
// over (grown if needed, 16 MiB at least: two 848x800 images' uploads share it).
VkDeviceSize VulkanBackend::claimStaging(VkDeviceSize bytes) {
  VkDeviceSize offset = aligned256(stagingUsed_);
  if (recordingFrame() || offset + bytes > staging_.size) {
    flush();  // the frame being recorded runs first; no submitted copy reads the staging buffer
    offset = 0;
  }
  if (staging_.size < bytes) {
    destroyBuffer(staging_);
    destroyBuffer(stagingMirror_);  // made again at the new size by the next byte upload
    staging_ = makeBuffer(std::max<VkDeviceSize>(bytes, VkDeviceSize(16) << 20), Memory::Staging);
  }
  stagingUsed_ = offset + bytes;
  return offset;
}

// The copy joins the immediate command buffer, its data in the persistently mapped
// staging buffer after the uploads before it: a frame's uploads go in one submission (the
// next flush: beginFrame, replayFrame, a download), not one round trip each. Queue order
// and the barrier before every command keep them after the work submitted before, and the
// frame (replayFrame submits it behind them without waiting) after them. `fill` writes the
// floats into the staging memory.
template <class Fill>
void VulkanBackend::copyFromStaging(const Buffer& dst, Fill&& fill) {
  const Alloc& a = alloc(dst);
  const VkDeviceSize bytes = dst.count() * sizeof(float);
  const VkDeviceSize offset = claimStaging(bytes);
  fill(reinterpret_cast<float*>(static_cast<char*>(staging_.mapped) + offset));
  VkCommandBuffer cb = recorder();
  barrier(cb, Cmd::Transfer);
  VkBufferCopy region{offset, a.offset, bytes};
  inst_.fn.vkCmdCopyBuffer(cb, staging_.buffer, arenas_[size_t(a.arena)].buffer, 1, &region);
}

void VulkanBackend::doUpload(const Buffer& dst, const float* host, bool* finite) {
  copyFromStaging(dst, [&](float* staged) { copyFloats(staged, host, dst.count(), finite); });
}

// The bytes cross the bus as they are, a quarter of the floats' bytes, and the device
// converts them (as CUDA's upload does): staged, copied to the same offset of the device's
// mirror of the staging buffer (whose claims keep regions apart while in use), then
// bytes_to_floats.comp looks each one up in the table of unitFromByte's floats (lut_), the
// host's bits by construction.
void VulkanBackend::doUploadBytes(const Buffer& dst, const uint8_t* host) {
  const size_t n = dst.count();
  if (n > size_t(UINT32_MAX) - 3) throw Error("vulkan backend: uploadBytes of more than 4 GiB");
  const VkDeviceSize bytes = (VkDeviceSize(n) + 3) & ~VkDeviceSize(3);  // whole words
  const VkDeviceSize offset = claimStaging(bytes);
  std::memcpy(static_cast<char*>(staging_.mapped) + offset, host, n);
  if (stagingMirror_.size != staging_.size) {  // not in use: claimStaging flushed before regrowing
    destroyBuffer(stagingMirror_);
    stagingMirror_ = makeBuffer(staging_.size, Memory::Device);
  }
  VkCommandBuffer cb = recorder();
  barrier(cb, Cmd::Transfer);
  const VkBufferCopy region{offset, offset, bytes};
  inst_.fn.vkCmdCopyBuffer(cb, staging_.buffer, stagingMirror_.buffer, 1, &region);
  const PcBytesToFloats pc{addr(dst), stagingMirror_.address + offset, lut_.address, uint32_t(n)};
  const uint32_t groups = uint32_t((bytes / 4 + 255) / 256);
  const uint32_t groupsX = std::min<uint32_t>(groups, 65535);
  dispatchGroups(kBytesToFloats, pc, groupsX, (groups + groupsX - 1) / groupsX);
}

// unitFromByte(v) for v = 0 .. 255 in lut_, written by the immediate command buffer's first
// command (the first submission runs it, before any byte upload's conversion).
void VulkanBackend::fillByteTable() {
  float table[256];
  for (int v = 0; v < 256; ++v) table[v] = unitFromByte(uint8_t(v));
  lut_ = makeBuffer(sizeof(table), Memory::Device);
  VkCommandBuffer cb = recorder();
  barrier(cb, Cmd::Transfer);
  inst_.fn.vkCmdUpdateBuffer(cb, lut_.buffer, 0, sizeof(table), table);
}

// One submission: the copy joins the immediate command buffer (after any uploads still
// there, in the staging buffer beyond theirs), behind the frame.
void VulkanBackend::doDownload(const Buffer& src, float* host) { doDownloadAll({{src, host}}); }

// Every copy in the one immediate command buffer, into one claim of the staging buffer, in
// pieces of at most kDownloadPiece bytes, each followed by an event (recordPieces); one
// submission, then the host copies each piece out of the staging buffer as soon as its
// event is set, while the later pieces still cross the bus (as CUDA's downloads do), and
// the fences are waited for as before (flush), the frame's and the copies' alike.
void VulkanBackend::doDownloadAll(const std::vector<Download>& downloads) {
  std::vector<Piece> pieces = downloadPieces(downloads);
  const VkDeviceSize total = pieces.empty() ? 0 : pieces.back().staged + pieces.back().bytes;
  const VkDeviceSize base = claimStaging(total);  // runs a frame being recorded first
  for (Piece& p : pieces) p.staged += base;
  recordPieces(pieces);
  submitImmediate();  // behind the frame in the queue: its first barrier waits for the frame
  copyPiecesOut(pieces);
}

constexpr VkDeviceSize kDownloadPiece = VkDeviceSize(1) << 18;  // 256 KiB: a piece per host thread

// The downloads' pieces in order, each buffer staged after the one before (256-aligned),
// from offset 0 of the region the caller claims.
std::vector<VulkanBackend::Piece> VulkanBackend::downloadPieces(const std::vector<Download>& downloads) {
  std::vector<Piece> pieces;
  VkDeviceSize staged = 0;
  for (const Download& d : downloads) {
    const Alloc& a = alloc(d.src);
    const VkDeviceSize bytes = d.src.count() * sizeof(float);
    for (VkDeviceSize at = 0; at < bytes; at += kDownloadPiece)
      pieces.push_back({reinterpret_cast<char*>(d.host) + at, arenas_[size_t(a.arena)].buffer, a.offset + at,
                        staged + at, std::min(kDownloadPiece, bytes - at)});
    staged += aligned256(bytes);
  }
  return pieces;
}

// Each piece's copy, then a barrier that makes its bytes available to the host and keeps
// the next copies behind it (the pieces arrive in order), then its event: set once the
// copy and the barrier before it are done, so a set event means the piece is there (the
// staging memory is host-coherent: nothing to invalidate). Events are reset by the host
// before recording: no pending command buffer uses them (every download waits for its own).
void VulkanBackend::recordPieces(const std::vector<Piece>& pieces) {
  auto eci = vkStruct<VkEventCreateInfo>(VK_STRUCTURE_TYPE_EVENT_CREATE_INFO);
  while (pieceEvents_.size() < pieces.size()) {
    VkEvent e;
    check(inst_.fn.vkCreateEvent(dev_, &eci, nullptr, &e), "vkCreateEvent");
    pieceEvents_.push_back(e);
  }
  for (size_t i = 0; i < pieces.size(); ++i) check(inst_.fn.vkResetEvent(dev_, pieceEvents_[i]), "vkResetEvent");
  VkCommandBuffer cb = recorder();
  barrier(cb, Cmd::Transfer);  // after the frame and everything else before
  auto mb = vkStruct<VkMemoryBarrier>(VK_STRUCTURE_TYPE_MEMORY_BARRIER);
  mb.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  mb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
  for (size_t i = 0; i < pieces.size(); ++i) {
    const VkBufferCopy region{pieces[i].srcOffset, pieces[i].staged, pieces[i].bytes};
    inst_.fn.vkCmdCopyBuffer(cb, pieces[i].src, staging_.buffer, 1, &region);
    inst_.fn.vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_TRANSFER_BIT,
                                  VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &mb, 0, nullptr, 0,
                                  nullptr);
    inst_.fn.vkCmdSetEvent(cb, pieceEvents_[i], VK_PIPELINE_STAGE_TRANSFER_BIT);
  }
}

// The pieces into the user's memory on the host's threads (detail::parallelFor), each as
// soon as its event is set, by the worker that polls it: the copies out overlap the later
// pieces' transfers and each other.
// Polling lasts at most spinNs_ from the start (none on a CPU device, whose work the
// polling would slow); past that the fences are waited for (flush: the frame's and the
// copies', with the hang timeout) and the pieces not yet copied are. flush() either way:
// every state back to idle. A worker may not throw: its errors are checked afterwards.
void VulkanBackend::copyPiecesOut(const std::vector<Piece>& pieces) {
  const auto start = std::chrono::steady_clock::now();
  auto copy = [&](const Piece& p) {
    std::memcpy(p.host, static_cast<const char*>(staging_.mapped) + p.staged, p.bytes);
  };
  std::vector<VkResult> polled(pieces.size(), VK_EVENT_RESET);
  detail::parallelFor(int(pieces.size()), [&](int i) {
    VkResult& r = polled[size_t(i)];
    spinUntil(start, spinNs_, [&] {
      r = inst_.fn.vkGetEventStatus(dev_, pieceEvents_[size_t(i)]);
      return r != VK_EVENT_RESET;
    });
    if (r == VK_EVENT_SET) copy(pieces[size_t(i)]);
  });
  for (VkResult r : polled)
    if (r != VK_EVENT_SET && r != VK_EVENT_RESET) check(r, "vkGetEventStatus");
  flush();
  detail::parallelFor(int(pieces.size()), [&](int i) {
    if (polled[size_t(i)] != VK_EVENT_SET) copy(pieces[size_t(i)]);
  });
}

void VulkanBackend::doFill(const Buffer& dst, float value) {
  const Alloc& a = alloc(dst);
  uint32_t bits;
  std::memcpy(&bits, &value, 4);
  VkCommandBuffer cb = recorder();
  barrier(cb, Cmd::Transfer);
  inst_.fn.vkCmdFillBuffer(cb, arenas_[size_t(a.arena)].buffer, a.offset, dst.count() * sizeof(float), bits);
}

void VulkanBackend::doCopy(const Buffer& dst, const Buffer& src) {
  VkCommandBuffer cb = recorder();
  barrier(cb, Cmd::Transfer);
  recordCopy(cb, dst, src);
}

void VulkanBackend::recordCopy(VkCommandBuffer cb, const Buffer& dst, const Buffer& src) {
  const Alloc& d = alloc(dst);
  const Alloc& s = alloc(src);
  VkBufferCopy region{s.offset, d.offset, src.count() * sizeof(float)};
  if (d.arena == s.arena && region.srcOffset == region.dstOffset) return;
  inst_.fn.vkCmdCopyBuffer(cb, arenas_[size_t(s.arena)].buffer, arenas_[size_t(d.arena)].buffer, 1, &region);
}

// Internal temporaries (the blurred image of the structure tensor, the sweep aggregation's
// three extra directions), one per size and slot.
Buffer VulkanBackend::scratch(int slot, int w, int h, int channels) {
  auto key = std::make_tuple(slot, w, h, channels);
  auto it = scratch_.find(key);
  if (it != scratch_.end()) return it->second;
  Frame was[kFrameSlots];  // a scratch buffer invalidates no recorded frame: they do not use it
  for (int i = 0; i < kFrameSlots; ++i) was[i] = frames_[i].state;
  Buffer b = create(w, h, channels);
  for (int i = 0; i < kFrameSlots; ++i) frames_[i].state = was[i];
  scratch_[key] = b;
  return b;
}

}  // namespace cs::vk
