// ROS 1 bag reader (format version 2.0, wiki.ros.org/Bags/Format/2.0): chunks uncompressed,
// bz2 or lz4. The index section (connections and chunk infos at the bag header's index_pos)
// lists the chunks when the bag was closed; a bag whose recorder died has none (index_pos 0
// or past the end) and is scanned record by record up to the cut.
#include <algorithm>
#include <map>

#include "log_reader.hpp"

namespace cs::logio {
namespace {

constexpr char kMagic[] = "#ROSBAG V2.0\n";
constexpr uint64_t kMagicBytes = 13;
enum Op : uint8_t {
  kMessage = 0x02,
  kBagHeader = 0x03,
  kIndex = 0x04,
  kChunk = 0x05,
  kChunkInfo = 0x06,
  kConnection = 0x07
};
constexpr uint64_t kMaxChunk = uint64_t(1) << 32;

// One record: its header's "name=value" fields and its data.
struct Record {
  std::map<std::string, std::pair<const uint8_t*, uint32_t>> fields;
  const uint8_t* data = nullptr;
  uint32_t dataSize = 0;
  uint64_t end = 0;  // offset after the record

  uint8_t op() const { return fieldBytes("op", 1)[0]; }
  const uint8_t* fieldBytes(const char* name, uint32_t size) const {
    const auto it = fields.find(name);
    if (it == fields.end() || it->second.second != size)
      throw Error(std::string("a record lacks its '") + name + "' field");
    return it->second.first;
  }
  template <typename T>
  T get(const char* name) const {
    T v;
    std::memcpy(&v, fieldBytes(name, sizeof v), sizeof v);
    return v;
  }
  std::string text(const char* name) const {
    const auto it = fields.find(name);
    if (it == fields.end()) throw Error(std::string("a record lacks its '") + name + "' field");
    return std::string(reinterpret_cast<const char*>(it->second.first), it->second.second);
  }
};

// "name=value" fields, each with a uint32 length (a record's header, a connection's data).
std::map<std::string, std::pair<const uint8_t*, uint32_t>> parseFields(const uint8_t* p, uint32_t n) {
  std::map<std::string, std::pair<const uint8_t*, uint32_t>> out;
  Bytes b(p, n);
  while (b.left()) {
    const uint32_t len = b.get<uint32_t>();
    b.need(len);
    const uint8_t* f = b.here();
    const uint8_t* eq = static_cast<const uint8_t*>(std::memchr(f, '=', len));
    if (!eq) throw Error("a record header field has no '='");
    out[std::string(reinterpret_cast<const char*>(f), size_t(eq - f))] = {eq + 1, uint32_t(len - (eq + 1 - f))};
    b.skip(len);
  }
  return out;
}

// The record at b's position; Truncated when it runs past the end.
Record readRecord(Bytes& b) {
  Record r;
  const uint32_t headerLen = b.get<uint32_t>();
  b.need(headerLen);
  r.fields = parseFields(b.here(), headerLen);
  b.skip(headerLen);
  r.dataSize = b.get<uint32_t>();
  b.need(r.dataSize);
  r.data = b.here();
  b.skip(r.dataSize);
  r.end = b.pos();
  return r;
}

class Ros1Reader : public Reader {
 public:
  explicit Ros1Reader(const std::string& path) : file_(path) {
    path_ = path;
    if (file_.size() < kMagicBytes || std::memcmp(file_.data(), kMagic, kMagicBytes) != 0)
      throw Error("'" + path + "' is not a ROS 1 bag of format 2.0 (no \"#ROSBAG V2.0\" line)");
    readIndex();
  }

  std::string format() const override {
    std::string c;
    for (const std::string& m : compressions_) c += (c.empty() ? "" : "+") + m;
    return "ROS 1 bag 2.0, " + (c.empty() ? std::string("no chunks") : c + " chunks") +
           (indexed_ ? ", indexed" : ", no index (scanned)");
  }

  void scan(const std::vector<bool>& wanted, const Visit& visit) override {
    wanted_ = wanted;
    if (indexed_) {
      decompressAhead(
          chunks_, [&](uint64_t offset) { return chunkData(offset); },
          [&](uint64_t offset, const ChunkData& data) { chunk(offset, data, visit); });
      return;
    }
    Bytes b(file_.data(), file_.size());
    b.skip(kMagicBytes);
    while (b.left()) {
      const uint64_t start = b.pos();
      Record r;
      try {
        r = readRecord(b);
      } catch (const Truncated&) {
        cut_ = "'" + path_ + "' is cut short at byte " + std::to_string(file_.size()) + " (inside the record at byte " +
               std::to_string(start) + "): read up to the cut";
        return;
      }
      const uint8_t op = guardedOp(r, start);
      if (op == kChunkInfo) return;  // the index section: every chunk was before it
      if (op == kChunk) chunk(start, chunkData(start), visit);
      if (op == kConnection) connection(r, start);
      if (op == kMessage) message(r, 0, r.data - file_.data(), visit, start);
    }
  }

  void read(const MessageRef& ref, const Use& use) const override {
    if (ref.chunk == 0) return use(file_.data() + ref.offset, size_t(ref.size));
    const ChunkData chunk = cache_.get(ref.chunk, [&] { return chunkData(ref.chunk); });
    if (ref.offset > chunk.size || ref.size > chunk.size - ref.offset)
      throw Error("corrupt ROS 1 bag " + at(ref.chunk) + ": the chunk changed since the bag was opened");
    use(chunk.data + ref.offset, size_t(ref.size));
  }

  uint64_t chunkLoads() const override { return cache_.loads(); }

 private:
  std::string at(uint64_t offset) const { return "'" + path_ + "' byte " + std::to_string(offset); }

  uint8_t guardedOp(const Record& r, uint64_t start) const {
    try {
      return r.op();
    } catch (const Error& e) {
      throw Error("corrupt ROS 1 bag " + at(start) + ": " + e.what());
    }
  }

  Record recordAt(uint64_t offset) const {
    if (offset >= file_.size()) throw Error("corrupt ROS 1 bag " + at(offset) + ": an index points outside the file");
    Bytes b(file_.data() + offset, file_.size() - offset);
    try {
      return readRecord(b);
    } catch (const Truncated&) {
      throw Error("corrupt ROS 1 bag " + at(offset) + ": a record runs past the end of the file");
    }
  }

  // The index section: connections and chunk infos after the chunks. Without one (index_pos 0
  // or outside the file: the recorder died) the bag is scanned.
  void readIndex() {
    Bytes b(file_.data(), file_.size());
    b.skip(kMagicBytes);
    uint64_t indexPos = 0;
    try {
      const Record h = readRecord(b);
      if (h.op() != kBagHeader) throw Error("the first record is not the bag header");
      indexPos = h.get<uint64_t>("index_pos");
    } catch (const Truncated&) {
      return;  // cut inside the bag header: scan finds nothing and says where
    } catch (const Error& e) {
      throw Error("corrupt ROS 1 bag '" + path_ + "': " + e.what());
    }
    if (indexPos <= kMagicBytes || indexPos >= file_.size()) return;
    try {
      Bytes i(file_.data() + indexPos, file_.size() - indexPos);
      while (i.left()) {
        const uint64_t start = indexPos + i.pos();
        const Record r = readRecord(i);
        const uint8_t op = r.op();
        if (op == kConnection) connection(r, start);
        if (op == kChunkInfo) chunks_.push_back(r.get<uint64_t>("chunk_pos"));
      }
    } catch (const Truncated&) {
      chunks_.clear();  // a damaged index: scan instead
    } catch (const Error& e) {
      throw Error("corrupt ROS 1 bag index '" + path_ + "': " + e.what());
    }
    std::sort(chunks_.begin(), chunks_.end());  // file order
    indexed_ = !chunks_.empty();
  }

  void connection(const Record& r, uint64_t start) {
    try {
      const uint32_t id = r.get<uint32_t>("conn");
      if (ids_.count(id)) return;
      const auto fields = parseFields(r.data, r.dataSize);
      const auto type = fields.find("type");
      if (type == fields.end()) throw Error("a connection has no type");
      ids_[id] = uint32_t(channels_.size());
      channels_.push_back(Channel{r.text("topic"),
                                  std::string(reinterpret_cast<const char*>(type->second.first), type->second.second),
                                  "ros1"});
    } catch (const Truncated&) {
      throw Error("corrupt ROS 1 bag " + at(start) + ": a connection record overruns itself");
    } catch (const Error& e) {
      throw Error("corrupt ROS 1 bag " + at(start) + ": " + e.what());
    }
  }

  // The chunk's records, decompressed unless stored plainly.
  ChunkData chunkData(uint64_t offset) const {
    const Record r = recordAt(offset);
    std::string compression;
    uint32_t uncompressed = 0;
    try {
      if (r.op() != kChunk) throw Error("no chunk where the index says");
      compression = r.text("compression");
      uncompressed = r.get<uint32_t>("size");
    } catch (const Error& e) {
      throw Error("corrupt ROS 1 bag " + at(offset) + ": " + e.what());
    }
    if (compression == "none") {
      if (uncompressed != r.dataSize) throw Error("corrupt ROS 1 bag " + at(offset) + ": chunk size mismatch");
      return ChunkData{nullptr, r.data, uncompressed};
    }
    if (uncompressed > kMaxChunk) throw Error("corrupt ROS 1 bag " + at(offset) + ": implausible chunk size");
    std::shared_ptr<uint8_t[]> buffer(new uint8_t[std::max<uint32_t>(uncompressed, 1)]);
    decompress(compression, r.data, r.dataSize, buffer.get(), uncompressed,
               "the chunk at byte " + std::to_string(offset) + " of ROS 1 bag '" + path_ + "'");
    return ChunkData{buffer, buffer.get(), uncompressed};
  }

  // A chunk's records (`chunk`: the chunk decompressed) in order.
  void chunk(uint64_t offset, const ChunkData& chunk, const Visit& visit) {
    const Record head = recordAt(offset);
    const std::string method = head.fields.count("compression") ? head.text("compression") : "?";
    if (std::find(compressions_.begin(), compressions_.end(), method) == compressions_.end())
      compressions_.push_back(method);
    visited_ = false;
    const uint8_t* data = chunk.data;
    Bytes b(data, chunk.size);
    while (b.left()) {
      const uint64_t start = b.pos();
      Record r;
      try {
        r = readRecord(b);
      } catch (const Truncated&) {
        throw Error("corrupt ROS 1 bag " + at(offset) + ": a record overruns its chunk");
      }
      const uint8_t op = guardedOp(r, offset);
      if (op == kConnection) connection(r, offset);
      if (op == kMessage) message(r, offset, uint64_t(r.data - data), visit, offset + start);
    }
    if (visited_ && keepChunks_) cache_.keep(offset, chunk);  // for read(): decompressed once
  }

  void message(const Record& r, uint64_t chunk, uint64_t offset, const Visit& visit, uint64_t where) {
    uint32_t id = 0;
    int64_t t = 0;
    try {
      id = r.get<uint32_t>("conn");
      const uint8_t* time = r.fieldBytes("time", 8);
      uint32_t sec, nsec;
      std::memcpy(&sec, time, 4);
      std::memcpy(&nsec, time + 4, 4);
      t = int64_t(sec) * 1'000'000'000 + nsec;
    } catch (const Error& e) {
      throw Error("corrupt ROS 1 bag " + at(where) + ": " + e.what());
    }
    const auto it = ids_.find(id);
    if (it == ids_.end())
      throw Error("corrupt ROS 1 bag " + at(where) + ": a message on connection " + std::to_string(id) +
                  ", which no connection record declares");
    Channel& c = channels_[it->second];
    if (!c.count || t < c.firstNs) c.firstNs = t;
    if (!c.count || t > c.lastNs) c.lastNs = t;
    ++c.count;
    if (!wanted_.empty() && !wanted_[it->second]) return;
    visited_ = true;
    visit(MessageRef{it->second, t, chunk, offset, r.dataSize}, r.data, r.dataSize);
  }

  MappedFile file_;
  std::map<uint32_t, uint32_t> ids_;  // connection id -> index in channels_
  std::vector<uint64_t> chunks_;
  std::vector<std::string> compressions_;
  std::vector<bool> wanted_;
  bool indexed_ = false, visited_ = false;  // visited_: the current chunk holds wanted messages
  mutable ChunkCache cache_;
};

}  // namespace

std::unique_ptr<Reader> openRos1(const std::string& path) { return std::make_unique<Ros1Reader>(path); }

}  // namespace cs::logio
