// McapWriter (mcap_writer.hpp): records as the MCAP specification lays them out.
#include <lz4frame.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <future>

#include "curvestereo/image.hpp"
#include "log_reader.hpp"
#include "mcap_format.hpp"
#include "mcap_writer.hpp"

namespace cs {
namespace {

using namespace mcap;  // kMagic, the opcodes

constexpr uint64_t kMessageFields = 2 + 4 + 8 + 8;  // channel, sequence, log time, publish time

template <typename T>
void put(std::vector<uint8_t>& b, T v) {
  const auto* c = reinterpret_cast<const uint8_t*>(&v);
  b.insert(b.end(), c, c + sizeof v);
}
void putStr(std::vector<uint8_t>& b, const std::string& s) {
  put(b, uint32_t(s.size()));
  b.insert(b.end(), s.begin(), s.end());
}
// A record: opcode, content length, content.
std::vector<uint8_t> record(uint8_t op, const std::vector<uint8_t>& content) {
  std::vector<uint8_t> r;
  r.reserve(content.size() + 9);
  put(r, op);
  put(r, uint64_t(content.size()));
  r.insert(r.end(), content.begin(), content.end());
  return r;
}

// Into `out`, whose memory is reused from chunk to chunk, as is zstd's context (`zstd`,
// made at the first chunk: a fresh one costs megabytes of new pages every chunk).
void compress(const std::string& method, const std::vector<uint8_t>& in, std::vector<uint8_t>& out, ZSTD_CCtx*& zstd,
              const std::string& path) {
  if (method == "zstd") {
    if (!zstd && !(zstd = ZSTD_createCCtx())) throw Error("writing MCAP '" + path + "': out of memory for zstd");
    out.resize(ZSTD_compressBound(in.size()));
    const size_t n = ZSTD_compressCCtx(zstd, out.data(), out.size(), in.data(), in.size(), 1);  // fast: depth is noisy
    if (ZSTD_isError(n)) throw Error("writing MCAP '" + path + "': zstd failed (" + ZSTD_getErrorName(n) + ")");
    out.resize(n);
  } else {
    LZ4F_preferences_t prefs{};
    prefs.frameInfo.contentSize = in.size();
    out.resize(LZ4F_compressFrameBound(in.size(), &prefs));
    const size_t n = LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), &prefs);
    if (LZ4F_isError(n)) throw Error("writing MCAP '" + path + "': lz4 failed (" + LZ4F_getErrorName(n) + ")");
    out.resize(n);
  }
}

}  // namespace

void CdrBuffer::header(int64_t stampNs, const std::string& frameId) {
  // builtin_interfaces/Time: floor seconds, so that nanosec stays in [0, 1e9).
  int64_t sec = stampNs / 1'000'000'000, nsec = stampNs % 1'000'000'000;
  if (nsec < 0) sec -= 1, nsec += 1'000'000'000;
  i32(int32_t(sec));
  u32(uint32_t(nsec));
  str(frameId);
}

McapWriter::McapWriter(const std::string& path, const std::string& compression, uint64_t chunkBytes)
    : path_(path),
      compression_(compression == "none" ? "" : compression),
      chunkBytes_(std::max<uint64_t>(chunkBytes, 1)) {
  if (compression != "none" && compression != "zstd" && compression != "lz4")
    throw Error("MCAP compression must be zstd, lz4 or none, got '" + logio::shown(compression) + "'");
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_) throw Error("cannot create MCAP file '" + path + "': " + std::strerror(errno));
  out(std::vector<uint8_t>(kMagic, kMagic + 8));
  std::vector<uint8_t> h;
  putStr(h, "ros2");
  putStr(h, "curvestereo");
  out(record(kHeader, h));
}

McapWriter::~McapWriter() {
  try {
    close();
  } catch (const Error& e) {
    std::fprintf(stderr, "curvestereo: %s\n", e.what());
  }
  closing_.clear();  // a failed close(): each chunk's worker is waited for before it goes
  if (file_) std::fclose(file_);
  for (ZSTD_CCtx* c : zstdContexts_) ZSTD_freeCCtx(c);
}

void McapWriter::out(const std::vector<uint8_t>& bytes) { out(bytes, logio::crc32(bytes.data(), bytes.size())); }

// bytesCrc: the CRC of `bytes` alone (a chunk's, computed as it was packed), folded into the
// running one without reading them again.
void McapWriter::out(const std::vector<uint8_t>& bytes, uint32_t bytesCrc) {
  if (!file_) throw Error("MCAP file '" + path_ + "' is closed");
  if (!bytes.empty() && std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size())
    throw Error("cannot write MCAP file '" + path_ + "': " + std::strerror(errno));
  uint32_t& crc = inData_ ? dataCrc_ : summaryCrc_;
  crc = logio::crc32Combine(crc, bytesCrc, bytes.size());
  pos_ += bytes.size();
}

uint16_t McapWriter::addSchema(const std::string& name, const std::string& encoding, const std::string& text) {
  const uint16_t id = uint16_t(schemas_.size() + 1);  // 0 means "no schema"
  std::vector<uint8_t> s;
  put(s, id);
  putStr(s, name);
  putStr(s, encoding);
  putStr(s, text);
  schemas_.push_back(record(kSchema, s));
  // Also in the data section, so that a reader scanning a file without summary finds it.
  chunk_.insert(chunk_.end(), schemas_.back().begin(), schemas_.back().end());
  return id;
}

uint16_t McapWriter::addChannel(uint16_t schema, const std::string& topic, const std::string& messageEncoding) {
  const uint16_t id = uint16_t(channels_.size());
  std::vector<uint8_t> c;
  put(c, id);
  put(c, schema);
  putStr(c, topic);
  putStr(c, messageEncoding);
  put(c, uint32_t(0));  // metadata: an empty map
  channels_.push_back(record(kChannel, c));
  chunk_.insert(chunk_.end(), channels_.back().begin(), channels_.back().end());
  counts_[id] = 0;
  return id;
}

void McapWriter::write(uint16_t channel, uint64_t logTimeNs, const std::vector<uint8_t>& data) {
  if (chunkIndex_.empty()) chunkStart_ = chunkEnd_ = logTimeNs;
  chunkStart_ = std::min(chunkStart_, logTimeNs);
  chunkEnd_ = std::max(chunkEnd_, logTimeNs);
  chunkIndex_[channel].emplace_back(logTimeNs, chunk_.size());
  // The Message record straight into the chunk (a frame's messages are about 14 MB: every
  // copy of them counts): opcode, length, channel, sequence, log and publish times, data.
  chunk_.reserve(chunk_.size() + 9 + kMessageFields + data.size());
  put(chunk_, uint8_t(kMessage));
  put(chunk_, uint64_t(kMessageFields + data.size()));
  put(chunk_, channel);
  put(chunk_, uint32_t(counts_[channel]));  // sequence
  put(chunk_, logTimeNs);
  put(chunk_, logTimeNs);  // publish time
  chunk_.insert(chunk_.end(), data.begin(), data.end());
  if (!messages_ || logTimeNs < firstNs_) firstNs_ = logTimeNs;
  if (!messages_ || logTimeNs > lastNs_) lastNs_ = logTimeNs;
  ++messages_;
  ++counts_[channel];
  if (chunk_.size() >= chunkBytes_) flushChunk();
}

// Packing (compression and the records' CRC) runs on a worker thread per chunk, so that a
// frame's chunks compress in parallel while the next messages fill the next chunk; the
// chunks are written in order, so the file does not depend on the threads.
void McapWriter::flushChunk() {
  if (chunk_.empty()) return;
  auto closed = std::make_unique<ClosedChunk>();
  closed->records.swap(chunk_);
  closed->index.swap(chunkIndex_);
  closed->start = chunkStart_;
  closed->end = chunkEnd_;
  if (!spareRecords_.empty()) {  // a written chunk's memory: no fresh pages to fault in
    chunk_.swap(spareRecords_.back());
    spareRecords_.pop_back();
  }
  ClosedChunk* c = closed.get();
  c->packing = std::async(std::launch::async, [this, c] { pack(*c); });
  closing_.push_back(std::move(closed));
  while (closing_.size() > kChunksInFlight) writeOldestChunk();
}

void McapWriter::pack(ClosedChunk& c) {
  c.recordsCrc = logio::crc32(c.records.data(), c.records.size());
  if (compression_.empty()) {
    c.packedCrc = c.recordsCrc;
    return;
  }
  ZSTD_CCtx* zstd = takeZstdContext();
  try {
    compress(compression_, c.records, c.packed, zstd, path_);
  } catch (...) {
    giveZstdContext(zstd);
    throw;
  }
  giveZstdContext(zstd);
  c.packedCrc = logio::crc32(c.packed.data(), c.packed.size());
}

ZSTD_CCtx* McapWriter::takeZstdContext() {
  const std::lock_guard<std::mutex> lock(zstdMutex_);
  if (zstdContexts_.empty()) return nullptr;  // compress() makes one
  ZSTD_CCtx* c = zstdContexts_.back();
  zstdContexts_.pop_back();
  return c;
}

void McapWriter::giveZstdContext(ZSTD_CCtx* context) {
  if (!context) return;
  const std::lock_guard<std::mutex> lock(zstdMutex_);
  zstdContexts_.push_back(context);
}

void McapWriter::writeOldestChunk() {
  ClosedChunk& c = *closing_.front();
  c.packing.get();  // rethrows a compression failure
  const std::vector<uint8_t>& packed = compression_.empty() ? c.records : c.packed;
  const uint64_t chunkOffset = pos_;
  // The Chunk record's fields, then its records as they are (not copied behind the fields).
  std::vector<uint8_t> fields;
  put(fields, uint8_t(kChunk));
  put(fields, uint64_t(8 + 8 + 8 + 4 + 4 + compression_.size() + 8 + packed.size()));
  put(fields, c.start);
  put(fields, c.end);
  put(fields, uint64_t(c.records.size()));
  put(fields, c.recordsCrc);
  putStr(fields, compression_);
  put(fields, uint64_t(packed.size()));
  out(fields);
  out(packed, c.packedCrc);
  const uint64_t chunkLength = pos_ - chunkOffset, indexStart = pos_;
  std::vector<uint8_t> offsets;  // the chunk index's map: channel -> its message index's offset
  for (const auto& [channel, entries] : c.index) {
    put(offsets, channel);
    put(offsets, pos_);
    std::vector<uint8_t> m;
    put(m, channel);
    put(m, uint32_t(entries.size() * 16));
    for (const auto& [t, offset] : entries) put(m, t), put(m, offset);
    out(record(kMessageIndex, m));
  }
  std::vector<uint8_t> ci;
  put(ci, c.start);
  put(ci, c.end);
  put(ci, chunkOffset);
  put(ci, chunkLength);
  put(ci, uint32_t(offsets.size()));
  ci.insert(ci.end(), offsets.begin(), offsets.end());
  put(ci, pos_ - indexStart);
  putStr(ci, compression_);
  put(ci, uint64_t(packed.size()));
  put(ci, uint64_t(c.records.size()));
  chunkIndexes_.push_back(record(kChunkIndex, ci));
  ++chunks_;
  c.records.clear();
  spareRecords_.push_back(std::move(c.records));
  closing_.pop_front();
}

void McapWriter::writeSummary() {
  const uint64_t summaryStart = pos_;
  std::vector<uint8_t> offsets;  // summary offset records, one per group
  const auto group = [&](uint8_t op, const std::vector<std::vector<uint8_t>>& records) {
    if (records.empty()) return;
    const uint64_t start = pos_;
    for (const auto& r : records) out(r);
    std::vector<uint8_t> o;
    put(o, op);
    put(o, start);
    put(o, pos_ - start);
    const auto r = record(kSummaryOffset, o);
    offsets.insert(offsets.end(), r.begin(), r.end());
  };
  group(kSchema, schemas_);
  group(kChannel, channels_);
  std::vector<uint8_t> st;
  put(st, messages_);
  put(st, uint16_t(schemas_.size()));
  put(st, uint32_t(channels_.size()));
  put(st, uint32_t(0));  // attachments
  put(st, uint32_t(0));  // metadata
  put(st, chunks_);
  put(st, firstNs_);
  put(st, lastNs_);
  put(st, uint32_t(counts_.size() * 10));
  for (const auto& [channel, n] : counts_) put(st, channel), put(st, n);
  group(kStatistics, {record(kStatistics, st)});
  group(kChunkIndex, chunkIndexes_);
  const uint64_t offsetStart = pos_;
  out(offsets);
  // The footer's CRC covers the summary and summary offsets and the footer up to that CRC.
  std::vector<uint8_t> f;
  put(f, uint8_t(kFooter));
  put(f, uint64_t(20));
  put(f, summaryStart);
  put(f, offsetStart);
  const uint32_t crc = logio::crc32(f.data(), f.size(), summaryCrc_);
  put(f, crc);
  out(f);
  out(std::vector<uint8_t>(kMagic, kMagic + 8));
}

void McapWriter::close() {
  if (!file_) return;
  flushChunk();
  while (!closing_.empty()) writeOldestChunk();
  std::vector<uint8_t> end;
  put(end, dataCrc_);
  out(record(kDataEnd, end));  // its own bytes are not in the CRC it carries: out() adds them after
  inData_ = false;
  writeSummary();
  const bool failed = std::fclose(file_) != 0;
  file_ = nullptr;
  if (failed) throw Error("cannot write MCAP file '" + path_ + "': " + std::strerror(errno));
}

}  // namespace cs
