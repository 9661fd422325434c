// MCAP reader (mcap.dev/spec, major version 0): chunks uncompressed, zstd or lz4; the
// summary's chunk indexes used when the file has them (chunks without wanted channels are
// skipped), a plain scan of the data section when not (a file cut short has no footer).
// CRCs are checked: the summary's, each chunk's, and in a plain scan the data section's.
#include <algorithm>
#include <map>

#include "log_reader.hpp"
#include "mcap_format.hpp"

namespace cs::logio {
namespace {

using namespace mcap;  // kMagic, the opcodes
constexpr uint64_t kFooterBytes = 1 + 8 + 20;      // opcode, length, three fields
constexpr uint64_t kMaxChunk = uint64_t(1) << 32;  // larger claims are corrupt, not allocated

struct ChunkHead {
  int64_t startNs = 0, endNs = 0;
  uint64_t uncompressedSize = 0;
  uint32_t crc = 0;
  std::string compression;
  uint64_t size = 0;  // of the (compressed) records
  const uint8_t* records = nullptr;
};

class McapReader : public Reader {
 public:
  explicit McapReader(const std::string& path) : file_(path) {
    path_ = path;
    if (file_.size() < 8 || std::memcmp(file_.data(), kMagic, 8) != 0)
      throw Error("'" + path + "' is not an MCAP file (no MCAP magic)");
    readSummary();
  }

  std::string format() const override {
    std::string c;
    for (const std::string& m : compressions_) c += (c.empty() ? "" : "+") + (m.empty() ? "uncompressed" : m);
    return "MCAP, " + (c.empty() ? std::string("no chunks") : c + " chunks") +
           (indexed_ ? ", summary and chunk indexes" : ", no index (scanned)");
  }

  void scan(const std::vector<bool>& wanted, const Visit& visit) override {
    wanted_ = wanted;
    if (!indexed_) return plainScan(visit);
    std::vector<uint64_t> wantedChunks;
    for (const auto& [offset, channels] : chunks_)
      if (anyWanted(channels)) wantedChunks.push_back(offset);
    decompressAhead(
        wantedChunks, [&](uint64_t offset) { return decompressChunk(offset, true); },
        [&](uint64_t offset, const ChunkData& chunk) { chunkRecords(offset, chunk, visit); });
  }

  void read(const MessageRef& ref, const Use& use) const override {
    if (ref.chunk == 0) return use(file_.data() + ref.offset, size_t(ref.size));
    // Its CRC passed in scan; a plain chunk is not cached (it is in the mapped file).
    const ChunkData chunk = cache_.get(ref.chunk, [&] { return decompressChunk(ref.chunk, false); });
    if (ref.offset > chunk.size || ref.size > chunk.size - ref.offset)
      throw Error("corrupt MCAP " + at(ref.chunk) + ": a message lies outside its chunk");
    use(chunk.data + ref.offset, size_t(ref.size));
  }

  uint64_t chunkLoads() const override { return cache_.loads(); }

 private:
  bool anyWanted(const std::vector<uint16_t>& ids) const {
    if (wanted_.empty()) return true;
    for (uint16_t id : ids)
      if (const auto it = ids_.find(id); it != ids_.end() && wanted_[it->second]) return true;
    return ids.empty();  // a chunk index without message indexes: read it to be sure
  }

  std::string at(uint64_t offset) const { return "'" + path_ + "' byte " + std::to_string(offset); }

  // The footer's summary: schemas, channels and chunk indexes. A file without one (or with
  // no chunk indexes) is scanned; a summary whose CRC fails is an error.
  void readSummary() {
    const uint64_t n = file_.size();
    if (n < 8 + kFooterBytes + 8 || std::memcmp(file_.data() + n - 8, kMagic, 8) != 0) return;
    const uint64_t footer = n - 8 - kFooterBytes;
    Bytes f(file_.data() + footer, kFooterBytes);
    if (f.get<uint8_t>() != kFooter || f.get<uint64_t>() != 20) return;
    const uint64_t summaryStart = f.get<uint64_t>(), summaryOffsetStart = f.get<uint64_t>();
    const uint32_t crc = f.get<uint32_t>();
    hasFooter_ = true;
    if (summaryStart == 0) return;
    if (summaryStart < 8 || summaryStart > footer || (summaryOffsetStart && summaryOffsetStart > footer))
      throw Error("corrupt MCAP " + at(footer) + ": the footer points outside the file");
    if (crc && crc32(file_.data() + summaryStart, footer + 1 + 8 + 16 - summaryStart) != crc)
      throw Error("bad CRC in the summary of MCAP '" + path_ + "' (byte " + std::to_string(summaryStart) +
                  " on): the file is corrupt");
    const uint64_t end = summaryOffsetStart ? summaryOffsetStart : footer;
    try {
      Bytes s(file_.data() + summaryStart, end - summaryStart);
      while (s.left()) {
        const uint8_t op = s.get<uint8_t>();
        const uint64_t len = s.get<uint64_t>();
        s.need(len);
        Bytes r(s.here(), len);
        if (op == kSchema) schema(r);
        if (op == kChannel) channel(r);
        if (op == kChunkIndex) chunkIndex(r);
        s.skip(len);
      }
    } catch (const Truncated&) {
      throw Error("corrupt MCAP " + at(summaryStart) + ": a summary record overruns the summary");
    }
    indexed_ = !chunks_.empty();
    for (const auto& [offset, ids] : chunks_) {
      std::string& topics = chunkTopics_[offset];
      for (uint16_t id : ids)
        if (const auto c = ids_.find(id); c != ids_.end())
          topics += (topics.empty() ? "" : ", ") + channels_[c->second].topic;
    }
  }

  void schema(Bytes& r) {
    const uint16_t id = r.get<uint16_t>();
    schemas_[id] = r.str32();
  }

  void channel(Bytes& r) {
    const uint16_t id = r.get<uint16_t>(), schema = r.get<uint16_t>();
    std::string topic = r.str32(), encoding = r.str32();
    if (ids_.count(id)) return;  // again in a chunk or the summary
    ids_[id] = uint32_t(channels_.size());
    const auto s = schemas_.find(schema);
    channels_.push_back(Channel{std::move(topic), s == schemas_.end() ? std::string() : s->second, encoding});
  }

  void chunkIndex(Bytes& r) {
    r.skip(16);  // message start and end time
    const uint64_t offset = r.get<uint64_t>();
    r.skip(8);  // chunk length
    const uint32_t mapBytes = r.get<uint32_t>();
    r.need(mapBytes);
    Bytes m(r.here(), mapBytes);
    std::vector<uint16_t> ids;
    while (m.left()) {
      ids.push_back(m.get<uint16_t>());
      m.skip(8);
    }
    r.skip(mapBytes);
    r.skip(8);
    const std::string compression = r.str32();
    if (std::find(compressions_.begin(), compressions_.end(), compression) == compressions_.end())
      compressions_.push_back(compression);
    if (offset < 8 || offset >= file_.size())
      throw Error("corrupt MCAP " + at(offset) + ": a chunk index points outside the file");
    chunks_[offset] = std::move(ids);
  }

  ChunkHead chunkHead(uint64_t offset) const {
    Bytes b(file_.data() + offset, file_.size() - offset);
    if (b.get<uint8_t>() != kChunk) throw Error("corrupt MCAP " + at(offset) + ": no chunk where its index says");
    const uint64_t len = b.get<uint64_t>();
    b.need(len);
    Bytes r(b.here(), len);
    ChunkHead h;
    try {
      h.startNs = int64_t(r.get<uint64_t>());
      h.endNs = int64_t(r.get<uint64_t>());
      h.uncompressedSize = r.get<uint64_t>();
      h.crc = r.get<uint32_t>();
      h.compression = r.str32();
      h.size = r.get<uint64_t>();
      r.need(h.size);
      h.records = r.here();
    } catch (const Truncated&) {
      throw Error("corrupt MCAP " + at(offset) + ": a chunk's fields overrun the chunk");
    }
    if (h.uncompressedSize > kMaxChunk || (h.compression.empty() && h.uncompressedSize != h.size))
      throw Error("corrupt MCAP " + at(offset) + ": implausible chunk size " + std::to_string(h.uncompressedSize));
    return h;
  }

  // A chunk, named in its error messages: where, when, and (from the index) its topics.
  // Reads only what is fixed once the summary is read (chunkTopics_): it runs on the
  // threads decompressing chunks while scan adds channels.
  std::string chunkName(uint64_t offset, const ChunkHead& h) const {
    const auto it = chunkTopics_.find(offset);
    return "the chunk at byte " + std::to_string(offset) + " of MCAP '" + path_ + "' (messages logged " +
           std::to_string(h.startNs) + " to " + std::to_string(h.endNs) + " ns" +
           (it == chunkTopics_.end() || it->second.empty() ? "" : " on " + it->second) + ")";
  }

  // A chunk's records, decompressed unless stored plainly; CRC checked.
  ChunkData decompressChunk(uint64_t offset, bool checkCrc) const {
    const ChunkHead h = chunkHead(offset);
    ChunkData chunk{nullptr, h.records, h.uncompressedSize};
    if (!h.compression.empty()) {
      std::shared_ptr<uint8_t[]> buffer(new uint8_t[std::max<uint64_t>(h.uncompressedSize, 1)]);
      decompress(h.compression, h.records, h.size, buffer.get(), h.uncompressedSize, chunkName(offset, h));
      chunk = ChunkData{buffer, buffer.get(), h.uncompressedSize};
    }
    if (checkCrc && h.crc && crc32(chunk.data, chunk.size) != h.crc)
      throw Error("bad CRC in " + chunkName(offset, h) + ": the log is corrupt");
    return chunk;
  }

  // A chunk's records visited in order (the chunk decompressed and its CRC checked).
  void chunkRecords(uint64_t offset, const ChunkData& chunk, const Visit& visit) {
    if (!indexed_) {  // the index listed them
      const std::string method = chunkHead(offset).compression;
      if (std::find(compressions_.begin(), compressions_.end(), method) == compressions_.end())
        compressions_.push_back(method);
    }
    Bytes b(chunk.data, chunk.size);
    visited_ = false;
    try {
      while (b.left()) {
        const uint64_t at = b.pos();
        const uint8_t op = b.get<uint8_t>();
        const uint64_t len = b.get<uint64_t>();
        b.need(len);
        record(op, b.here(), len, offset, at + 9, visit);
        b.skip(len);
      }
    } catch (const Truncated&) {
      throw Error("corrupt MCAP " + at(offset) + ": a record overruns its chunk");
    }
    if (visited_ && keepChunks_) cache_.keep(offset, chunk);  // for read(): decompressed once
  }

  // One data-section record (in a chunk when chunk != 0; `where`: its content's offset).
  void record(uint8_t op, const uint8_t* p, uint64_t len, uint64_t chunk, uint64_t where, const Visit& visit) {
    Bytes r(p, len);
    if (op == kSchema) schema(r);
    if (op == kChannel) channel(r);
    if (op != kMessage) return;
    const uint16_t id = r.get<uint16_t>();
    r.skip(4);  // sequence
    const uint64_t logTime = r.get<uint64_t>();
    r.skip(8);  // publish time
    const auto it = ids_.find(id);
    if (it == ids_.end())
      throw Error("corrupt MCAP " + at(chunk ? chunk : where) + ": a message on channel " + std::to_string(id) +
                  ", which no channel record declares");
    Channel& c = channels_[it->second];
    if (!c.count || int64_t(logTime) < c.firstNs) c.firstNs = int64_t(logTime);
    if (!c.count || int64_t(logTime) > c.lastNs) c.lastNs = int64_t(logTime);
    ++c.count;
    if (!wanted_.empty() && !wanted_[it->second]) return;
    const MessageRef ref{it->second, int64_t(logTime), chunk, where + r.pos(), r.left()};
    visited_ = true;
    visit(ref, r.here(), size_t(r.left()));
  }

  void plainScan(const Visit& visit) {
    const uint64_t n = file_.size();
    Bytes b(file_.data(), n);
    b.skip(8);
    while (true) {
      const uint64_t start = b.pos();
      if (b.left() == 0) return noteCut(start, "at a record boundary");
      uint8_t op;
      uint64_t len;
      try {
        op = b.get<uint8_t>();
        len = b.get<uint64_t>();
        b.need(len);
      } catch (const Truncated&) {
        return noteCut(start, "inside a record's head");
      }
      if (len > n) return noteCut(start, "inside a record");
      if (op == kDataEnd) return dataEnd(start, b);
      if (op == kFooter) return;
      if (op == kChunk) {
        chunks_[start];
        chunkRecords(start, decompressChunk(start, true), visit);
      } else {
        try {
          record(op, b.here(), len, 0, b.pos(), visit);
        } catch (const Truncated&) {
          throw Error("corrupt MCAP " + at(start) + ": a record's fields overrun it");
        }
      }
      b.skip(len);
    }
  }

  void dataEnd(uint64_t start, Bytes& b) {
    const uint32_t crc = b.left() >= 4 ? b.get<uint32_t>() : 0;
    if (crc && crc32(file_.data(), start) != crc)
      throw Error("bad CRC in the data section of MCAP '" + path_ + "' (bytes 0 to " + std::to_string(start) +
                  "): the log is corrupt");
    if (!hasFooter_)
      cut_ = "'" + path_ + "' is cut short after its data section (at byte " + std::to_string(file_.size()) +
             "): every message is there, the summary is not";
  }

  void noteCut(uint64_t recordStart, const char* where) {
    cut_ = "'" + path_ + "' is cut short at byte " + std::to_string(file_.size()) + " (" + where + " at byte " +
           std::to_string(recordStart) + "): read up to the cut";
  }

  MappedFile file_;
  std::map<uint16_t, std::string> schemas_;
  std::map<uint16_t, uint32_t> ids_;                  // channel id -> index in channels_
  std::map<uint64_t, std::vector<uint16_t>> chunks_;  // chunk offset -> its channels (from the index)
  std::map<uint64_t, std::string> chunkTopics_;       // chunk offset -> its topics, for messages
  std::vector<std::string> compressions_;
  std::vector<bool> wanted_;
  bool indexed_ = false, hasFooter_ = false;
  bool visited_ = false;  // the chunk being scanned holds wanted messages
  mutable ChunkCache cache_;
};

}  // namespace

std::unique_ptr<Reader> openMcap(const std::string& path) { return std::make_unique<McapReader>(path); }

}  // namespace cs::logio
