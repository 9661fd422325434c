// An MCAP writer (mcap.dev/spec) and ROS 2 CDR serialisation, for DepthLogWriter and
// writeImageLog (log_writer.cpp). Chunked (uncompressed, zstd or lz4), each chunk followed by
// its message indexes; close() adds the data-section CRC, a summary (schemas, channels,
// statistics, chunk indexes), summary offsets and the footer with the summary's CRC.
#pragma once
#include <cstdint>
#include <cstdio>
#include <deque>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

struct ZSTD_CCtx_s;  // zstd.h's compression context

namespace cs {

// CDR, little-endian, with its encapsulation header; primitives aligned to their size from
// the end of that header.
class CdrBuffer {
 public:
  CdrBuffer() : b_{0, 1, 0, 0} {}
  void u8(uint8_t v) { b_.push_back(v); }
  void u32(uint32_t v) { put(v); }
  void i32(int32_t v) { put(v); }
  void f64(double v) { put(v); }
  void str(const std::string& s) {  // length counts the NUL
    u32(uint32_t(s.size() + 1));
    b_.insert(b_.end(), s.begin(), s.end());
    b_.push_back(0);
  }
  void bytes(const void* p, size_t n) {
    u32(uint32_t(n));
    const auto* c = static_cast<const uint8_t*>(p);
    b_.insert(b_.end(), c, c + n);
  }
  void header(int64_t stampNs, const std::string& frameId);  // std_msgs/Header
  const std::vector<uint8_t>& data() const { return b_; }

 private:
  template <typename T>
  void put(T v) {
    while ((b_.size() - 4) % sizeof(T)) b_.push_back(0);
    const auto* c = reinterpret_cast<const uint8_t*>(&v);
    b_.insert(b_.end(), c, c + sizeof v);
  }
  std::vector<uint8_t> b_;
};

class McapWriter {
 public:
  // compression: "zstd", "lz4" or "none". Throws cs::Error when the file cannot be created.
  McapWriter(const std::string& path, const std::string& compression, uint64_t chunkBytes);
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;
  uint16_t addSchema(const std::string& name, const std::string& encoding, const std::string& text);
  uint16_t addChannel(uint16_t schema, const std::string& topic, const std::string& messageEncoding);
  void write(uint16_t channel, uint64_t logTimeNs, const std::vector<uint8_t>& data);
  void close();  // idempotent

 private:
  // A chunk whose records are packed (compressed, CRCs) on a worker thread.
  struct ClosedChunk {
    std::vector<uint8_t> records, packed;
    std::map<uint16_t, std::vector<std::pair<uint64_t, uint64_t>>> index;  // channel -> (time, offset)
    uint64_t start = 0, end = 0;
    uint32_t recordsCrc = 0, packedCrc = 0;
    std::future<void> packing;
  };
  static constexpr size_t kChunksInFlight = 4;  // packed at once; the oldest is written first

  void out(const std::vector<uint8_t>& bytes);
  void out(const std::vector<uint8_t>& bytes, uint32_t bytesCrc);
  void flushChunk();
  void pack(ClosedChunk& chunk);  // on the chunk's worker thread
  void writeOldestChunk();
  ZSTD_CCtx_s* takeZstdContext();  // a reused context, or null
  void giveZstdContext(ZSTD_CCtx_s* context);
  void writeSummary();

  std::string path_;
  std::string compression_;
  uint64_t chunkBytes_;
  std::FILE* file_ = nullptr;
  uint64_t pos_ = 0;
  uint32_t dataCrc_ = 0, summaryCrc_ = 0;
  bool inData_ = true;  // the data section's bytes feed dataCrc_, the summary's summaryCrc_
  // the open chunk
  std::vector<uint8_t> chunk_;
  std::deque<std::unique_ptr<ClosedChunk>> closing_;  // being packed, in file order
  std::vector<std::vector<uint8_t>> spareRecords_;    // written chunks' memory, for new chunks
  std::mutex zstdMutex_;
  std::vector<ZSTD_CCtx_s*> zstdContexts_;  // zstd's contexts, reused from chunk to chunk
  uint64_t chunkStart_ = 0, chunkEnd_ = 0;
  std::map<uint16_t, std::vector<std::pair<uint64_t, uint64_t>>> chunkIndex_;  // channel -> (time, offset)
  // the summary
  std::vector<std::vector<uint8_t>> schemas_, channels_, chunkIndexes_;
  std::map<uint16_t, uint64_t> counts_;
  uint64_t messages_ = 0, firstNs_ = 0, lastNs_ = 0;
  uint32_t chunks_ = 0;
};

}  // namespace cs
