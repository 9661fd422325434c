// The readers of recorded logs (log.hpp), behind one interface: each lists its channels,
// walks its messages in file order once (scan) and later reads single messages again (read).
// One reader per file: log_mcap.cpp, log_ros1.cpp, log_rosbag2.cpp; the message decoding
// (CDR, ROS 1) is log_messages.cpp's.
#pragma once
#include <cstdint>
#include <cstring>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "curvestereo/image.hpp"

namespace cs::logio {

struct Channel {
  std::string topic, type;
  std::string encoding;  // "cdr" (ROS 2), "ros1", or another (then not readable here)
  bool cdr() const { return encoding == "cdr"; }
  uint64_t count = 0;
  int64_t firstNs = 0, lastNs = 0;  // log times
};

// Where a message lies: in a chunk (chunk = the chunk record's file offset, offset = within
// its decompressed records) or directly in the file (chunk = 0, offset = file offset); for
// sqlite, chunk is the database's index and offset the row id.
struct MessageRef {
  uint32_t channel = 0;  // index into Reader::channels()
  int64_t logTimeNs = 0;
  uint64_t chunk = 0, offset = 0;
  uint64_t size = 0;
};

using Visit = std::function<void(const MessageRef&, const uint8_t* data, size_t size)>;
using Use = std::function<void(const uint8_t* data, size_t size)>;

class Reader {
 public:
  virtual ~Reader() = default;
  virtual std::string format() const = 0;  // "MCAP, zstd chunks", ...
  // Every message in file order (wanted: channel indexes to visit, all when empty). A log cut
  // short is read up to the cut, which cut() then describes; corruption throws cs::Error.
  virtual void scan(const std::vector<bool>& wanted, const Visit& visit) = 0;
  // One message again; `use` sees its bytes (valid during the call). Thread-safe.
  virtual void read(const MessageRef& ref, const Use& use) const = 0;
  // Chunks read() had to decompress, not finding them kept from scan (for tests).
  virtual uint64_t chunkLoads() const { return 0; }
  // Whether scan keeps its decompressed chunks for read() (ChunkCache); off for a listing
  // (logInfo), which reads no message again.
  void keepChunks(bool keep) { keepChunks_ = keep; }
  const std::vector<Channel>& channels() const { return channels_; }
  const std::string& cut() const { return cut_; }
  const std::string& path() const { return path_; }

 protected:
  std::vector<Channel> channels_;
  std::string cut_, path_;
  bool keepChunks_ = true;
};

// Opens by content: MCAP magic, "#ROSBAG V2.0", SQLite, or a rosbag2 folder (metadata.yaml).
std::unique_ptr<Reader> openReader(const std::string& path);
std::unique_ptr<Reader> openMcap(const std::string& path);
std::unique_ptr<Reader> openRos1(const std::string& path);
std::unique_ptr<Reader> openRosbag2(const std::string& path);

// ---- shared helpers (log_messages.cpp)

// A read-only view of a whole file (mmap), so that readers index it without copies.
class MappedFile {
 public:
  explicit MappedFile(const std::string& path);
  ~MappedFile();
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  const uint8_t* data() const { return data_; }
  uint64_t size() const { return size_; }

 private:
  const uint8_t* data_ = nullptr;
  uint64_t size_ = 0;
};

// Little-endian fields with bounds checks: a field past the end throws Truncated, which the
// readers turn into "cut at byte N" or a corrupt-record error.
struct Truncated {
  uint64_t need;
};
class Bytes {
 public:
  Bytes(const uint8_t* p, uint64_t n) : p_(p), n_(n) {}
  uint64_t left() const { return n_ - pos_; }
  uint64_t pos() const { return pos_; }
  const uint8_t* here() const { return p_ + pos_; }
  void skip(uint64_t k) {
    need(k);
    pos_ += k;
  }
  template <typename T>
  T get() {
    need(sizeof(T));
    T v;
    std::memcpy(&v, p_ + pos_, sizeof v);  // the formats are little-endian, as is every target
    pos_ += sizeof v;
    return v;
  }
  std::string str32() {  // MCAP string: uint32 length + bytes
    const uint32_t n = get<uint32_t>();
    need(n);
    std::string s(reinterpret_cast<const char*>(p_ + pos_), n);
    pos_ += n;
    return s;
  }
  void need(uint64_t k) const {
    if (k > n_ - pos_) throw Truncated{k - (n_ - pos_)};
  }

 private:
  const uint8_t* p_;
  uint64_t n_, pos_ = 0;
};

// A chunk's records: decompressed into `owner`, or (stored plainly) in the mapped file.
struct ChunkData {
  std::shared_ptr<const uint8_t[]> owner;
  const uint8_t* data = nullptr;
  uint64_t size = 0;
};

// Decompressed chunks, so that each is decompressed once: scan (which must decompress every
// chunk for the messages' header stamps) hands its chunks over while they fit the budget,
// keeping the first ones, which the frames read first need; read() then finds them, and
// decompresses later ones once each, evicting the least recently used. Chunks are read in
// file order and a chunk holds neighbouring frames, so a small budget suffices. Distinct
// chunks are decompressed concurrently (for the threads that read frames ahead); a thread
// wanting a chunk another is decompressing waits for it instead of doing it again.
class ChunkCache {
 public:
  using Load = std::function<ChunkData()>;
  explicit ChunkCache(uint64_t budgetBytes = uint64_t(256) << 20) : budget_(budgetBytes) {}
  ChunkData get(uint64_t key, const Load& load);
  void keep(uint64_t key, const ChunkData& chunk);  // from scan: kept only while under budget
  uint64_t loads() const {                          // chunks get() had to load, not finding them (for tests)
    std::lock_guard<std::mutex> lock(mutex_);
    return loads_;
  }

 private:
  struct Entry {
    std::shared_future<ChunkData> chunk;
    uint64_t bytes = 0, used = 0;  // bytes: 0 until loaded
  };
  void evict(uint64_t keep);

  mutable std::mutex mutex_;
  std::map<uint64_t, Entry> entries_;
  uint64_t budget_, bytes_ = 0, clock_ = 0, loads_ = 0;
};

// Opening a log decompresses every chunk holding wanted messages (for their header stamps),
// which is most of its cost (bz2 above all), so the chunks of an indexed log are
// decompressed on up to `threads` threads (0: the hardware's, at most 8) a few chunks ahead,
// and used in file order on the calling thread (their records parsed, the messages visited).
// An error is raised at its chunk's turn, so the first corrupt chunk in file order is named.
// `decompress` must be thread-safe.
void decompressAhead(const std::vector<uint64_t>& chunks, const std::function<ChunkData(uint64_t)>& decompress,
                     const std::function<void(uint64_t, const ChunkData&)>& use, unsigned threads = 0);

uint32_t crc32(const uint8_t* p, uint64_t n, uint32_t crc = 0);
// The CRC of A followed by B from crc32(A), crc32(B) and B's length (zlib's crc32_combine).
uint32_t crc32Combine(uint32_t crcA, uint32_t crcB, uint64_t lengthB);
// Decompresses a whole buffer of a known size ("zstd", "lz4" frame, "bz2"); throws cs::Error
// naming `what` when the data is corrupt or decompresses to another size.
void decompress(const std::string& method, const uint8_t* in, uint64_t inSize, uint8_t* out, uint64_t outSize,
                const std::string& what);
// Text from a file, shown in a one-line message: bounded, control characters replaced.
std::string shown(const std::string& text, size_t max = 60);

// ---- messages

enum class ImageKind { None, Raw, Compressed };
ImageKind imageKind(const std::string& type);  // sensor_msgs/(msg/)Image or CompressedImage
// The header.stamp of a message with a std_msgs/Header first (Image, CompressedImage).
int64_t headerStampNs(const uint8_t* p, size_t n, bool cdr);
// The image's encoding (raw) or format (compressed), for the checks at opening.
std::string imageEncoding(const uint8_t* p, size_t n, bool cdr, ImageKind kind);
bool supportedEncoding(const std::string& encoding, ImageKind kind);
// The message as float gray in [0, 1], as readPngGray converts the same pixels.
void decodeImage(const uint8_t* p, size_t n, bool cdr, ImageKind kind, ImageF& out);

}  // namespace cs::logio
