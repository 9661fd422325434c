// What the log readers share (log_reader.hpp): the mapped file, CRC-32, decompression, and
// the sensor_msgs image messages in ROS 2 CDR and ROS 1 serialisation.
#include <bzlib.h>
#include <fcntl.h>
#include <lz4frame.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <csetjmp>
#include <cstdio>

#include "curvestereo/image_io.hpp"
#include "log_reader.hpp"

#ifdef CS_HAVE_JPEG
#include <jpeglib.h>
#endif

namespace cs::logio {

MappedFile::MappedFile(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw Error("cannot open log '" + path + "': " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw Error("log '" + path + "' is not a regular file");
  }
  size_ = uint64_t(st.st_size);
  if (size_) {
    void* p = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
    if (p == MAP_FAILED) {
      const int err = errno;
      ::close(fd);
      throw Error("cannot map log '" + path + "': " + std::strerror(err));
    }
    data_ = static_cast<const uint8_t*>(p);
  }
  ::close(fd);  // the mapping keeps the file
}

MappedFile::~MappedFile() {
  if (data_) ::munmap(const_cast<uint8_t*>(data_), size_);
}

uint32_t crc32(const uint8_t* p, uint64_t n, uint32_t crc) {
  // zlib's CRC-32 is the one MCAP specifies (IEEE 802.3); zlib takes uInt-sized pieces.
  while (n) {
    const uInt piece = uInt(std::min<uint64_t>(n, 1u << 30));
    crc = uint32_t(::crc32(crc, p, piece));
    p += piece, n -= piece;
  }
  return crc;
}

uint32_t crc32Combine(uint32_t crcA, uint32_t crcB, uint64_t lengthB) {
  return uint32_t(::crc32_combine(crcA, crcB, z_off_t(lengthB)));  // z_off_t: 64 bits on LP64
}

std::string shown(const std::string& text, size_t max) {
  std::string s = text.size() > max ? text.substr(0, max) + "..." : text;
  for (char& c : s)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  return s;
}

namespace {

void lz4Decompress(const uint8_t* in, uint64_t inSize, uint8_t* out, uint64_t outSize, const std::string& what) {
  LZ4F_dctx* ctx = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION))) throw Error(what + ": lz4 context failed");
  uint64_t inPos = 0, outPos = 0;
  size_t rc = 1;
  while (rc != 0 && inPos < inSize) {
    size_t inChunk = size_t(inSize - inPos), outChunk = size_t(outSize - outPos);
    rc = LZ4F_decompress(ctx, out + outPos, &outChunk, in + inPos, &inChunk, nullptr);
    if (LZ4F_isError(rc)) {
      LZ4F_freeDecompressionContext(ctx);
      throw Error(what + ": corrupt lz4 data (" + LZ4F_getErrorName(rc) + ")");
    }
    if (inChunk == 0 && outChunk == 0) break;  // no progress: the output is full or the input ends
    inPos += inChunk, outPos += outChunk;
  }
  LZ4F_freeDecompressionContext(ctx);
  if (outPos != outSize)
    throw Error(what + ": lz4 data gives " + std::to_string(outPos) + " bytes, not " + std::to_string(outSize));
}

}  // namespace

void decompress(const std::string& method, const uint8_t* in, uint64_t inSize, uint8_t* out, uint64_t outSize,
                const std::string& what) {
  if (method == "zstd") {
    const size_t got = ZSTD_decompress(out, outSize, in, inSize);
    if (ZSTD_isError(got)) throw Error(what + ": corrupt zstd data (" + ZSTD_getErrorName(got) + ")");
    if (got != outSize)
      throw Error(what + ": zstd data gives " + std::to_string(got) + " bytes, not " + std::to_string(outSize));
  } else if (method == "lz4") {
    lz4Decompress(in, inSize, out, outSize, what);
  } else if (method == "bz2") {
    if (inSize > UINT32_MAX || outSize > UINT32_MAX) throw Error(what + ": bz2 block over 4 GiB");
    unsigned got = unsigned(outSize);
    const int rc =
        BZ2_bzBuffToBuffDecompress(reinterpret_cast<char*>(out), &got,
                                   const_cast<char*>(reinterpret_cast<const char*>(in)), unsigned(inSize), 0, 0);
    if (rc != BZ_OK) throw Error(what + ": corrupt bz2 data (error " + std::to_string(rc) + ")");
    if (got != outSize)
      throw Error(what + ": bz2 data gives " + std::to_string(got) + " bytes, not " + std::to_string(outSize));
  } else {
    throw Error(what + ": unsupported compression '" + shown(method) + "' (zstd, lz4, bz2 or none)");
  }
}

// ---------------------------------------------------------------- messages

namespace {

// A sensor_msgs message's fields in either serialisation. CDR aligns each primitive to its
// size, counted from the end of the 4-byte encapsulation header; CDR strings carry their NUL
// in the length. ROS 1 packs fields without alignment.
class Fields {
 public:
  Fields(const uint8_t* p, size_t n, bool cdr) : b_(p, n), cdr_(cdr) {
    if (!cdr_) return;
    const uint8_t head0 = b_.get<uint8_t>(), kind = b_.get<uint8_t>();
    b_.skip(2);
    if (head0 != 0 || (kind != 0 && kind != 1))
      throw Error("not a CDR message (encapsulation " + std::to_string(head0) + "," + std::to_string(kind) + ")");
    if (kind == 0) throw Error("big-endian CDR is not supported");
  }
  uint32_t u32() {
    align(4);
    return b_.get<uint32_t>();
  }
  uint8_t u8() { return b_.get<uint8_t>(); }
  std::string str() {
    const uint32_t n = u32();
    b_.need(n);
    std::string s(reinterpret_cast<const char*>(b_.here()), n);
    b_.skip(n);
    if (cdr_ && !s.empty() && s.back() == 0) s.pop_back();
    return s;
  }
  // A uint8[] field: its bytes stay in the message.
  std::pair<const uint8_t*, size_t> bytes() {
    const uint32_t n = u32();
    b_.need(n);
    const uint8_t* p = b_.here();
    b_.skip(n);
    return {p, n};
  }
  // std_msgs/Header (ROS 1: seq first; stamp seconds signed in ROS 2, unsigned in ROS 1).
  int64_t header() {
    if (!cdr_) u32();  // seq
    const uint32_t sec = u32(), nsec = u32();
    str();  // frame_id
    const int64_t s = cdr_ ? int64_t(int32_t(sec)) : int64_t(sec);
    return s * 1'000'000'000 + int64_t(nsec);
  }

 private:
  void align(size_t k) {
    if (cdr_) b_.skip((k - (b_.pos() - 4) % k) % k);
  }
  Bytes b_;
  bool cdr_;
};

// Truncated fields inside a message are a corrupt message, not a cut log.
template <typename F>
auto guarded(F&& f) {
  try {
    return f();
  } catch (const Truncated&) {
    throw Error("message ends inside its fields (corrupt or not the declared type)");
  }
}

struct RawImage {
  uint32_t height = 0, width = 0, step = 0;
  std::string encoding;
  bool bigEndian = false;
  std::pair<const uint8_t*, size_t> data;
};

RawImage parseRaw(Fields& f) {
  RawImage im;
  f.header();
  im.height = f.u32();
  im.width = f.u32();
  im.encoding = f.str();
  im.bigEndian = f.u8() != 0;
  im.step = f.u32();
  im.data = f.bytes();
  return im;
}

int bytesPerPixel(const std::string& e) {
  if (e == "mono8" || e == "8UC1") return 1;
  if (e == "mono16" || e == "16UC1") return 2;
  if (e == "rgb8" || e == "bgr8") return 3;
  return 0;
}

// The PNG reader's conversions (pngSample, convertRowToGray), so that a log's pixels give
// exactly the floats their PNG files give: float(v / 255.0) and float(v / 65535.0).
const std::array<float, 256>& table8() {
  static const std::array<float, 256> t = [] {
    std::array<float, 256> a{};
    for (int v = 0; v < 256; ++v) a[size_t(v)] = float(v / 255.0);
    return a;
  }();
  return t;
}
const std::vector<float>& table16() {
  static const std::vector<float> t = [] {
    std::vector<float> a(65536);
    for (int v = 0; v < 65536; ++v) a[size_t(v)] = float(v / 65535.0);
    return a;
  }();
  return t;
}

void convertRaw(const RawImage& im, ImageF& out) {
  const int bpp = bytesPerPixel(im.encoding);
  if (!bpp) throw Error("unsupported encoding '" + shown(im.encoding) + "' (mono8, mono16, rgb8, bgr8)");
  if (im.width == 0 || im.height == 0 || im.width > 65536 || im.height > 65536)
    throw Error("implausible image size " + std::to_string(im.width) + "x" + std::to_string(im.height));
  if (uint64_t(im.step) < uint64_t(im.width) * bpp || uint64_t(im.step) * im.height > im.data.second)
    throw Error("image data (" + std::to_string(im.data.second) + " bytes, step " + std::to_string(im.step) +
                ") is too small for " + std::to_string(im.width) + "x" + std::to_string(im.height) + " " + im.encoding);
  if (out.width != int(im.width) || out.height != int(im.height)) out = ImageF(int(im.width), int(im.height));
  const auto& t8 = table8();
  for (uint32_t y = 0; y < im.height; ++y) {
    const uint8_t* row = im.data.first + size_t(y) * im.step;
    float* o = out.data.data() + size_t(y) * im.width;
    if (bpp == 1) {
      for (uint32_t x = 0; x < im.width; ++x) o[x] = t8[row[x]];
    } else if (bpp == 2) {
      const auto& t16 = table16();
      for (uint32_t x = 0; x < im.width; ++x)
        o[x] =
            t16[im.bigEndian ? unsigned(row[2 * x]) << 8 | row[2 * x + 1] : unsigned(row[2 * x + 1]) << 8 | row[2 * x]];
    } else {
      const bool bgr = im.encoding == "bgr8";
      for (uint32_t x = 0; x < im.width; ++x) {
        const uint8_t* px = row + 3 * x;
        const float r = t8[px[bgr ? 2 : 0]], g = t8[px[1]], b = t8[px[bgr ? 0 : 2]];
        o[x] = float(std::min(1.0, 0.299 * r + 0.587 * g + 0.114 * b));  // Rec. 601, as the PNG reader
      }
    }
  }
}

#ifdef CS_HAVE_JPEG
struct JpegError {
  jpeg_error_mgr mgr;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

[[noreturn]] void onJpegError(j_common_ptr info) {
  auto* e = reinterpret_cast<JpegError*>(info->err);
  (*info->err->format_message)(info, e->message);
  std::longjmp(e->jump, 1);
}

// libjpeg's grey output is the luma it decodes (JPEG's Y is Rec. 601 luma).
bool decodeJpegRows(jpeg_decompress_struct* d, const uint8_t* p, size_t n, ImageF& out, JpegError* err) {
  if (setjmp(err->jump)) return false;
  jpeg_mem_src(d, p, static_cast<unsigned long>(n));
  jpeg_read_header(d, TRUE);
  d->out_color_space = JCS_GRAYSCALE;
  jpeg_start_decompress(d);
  if (d->output_width == 0 || d->output_width > 65536 || d->output_height > 65536) {
    std::snprintf(err->message, sizeof err->message, "implausible JPEG size");
    return false;
  }
  out = ImageF(int(d->output_width), int(d->output_height));
  std::vector<uint8_t> row(d->output_width);
  const auto& t8 = table8();
  while (d->output_scanline < d->output_height) {
    const size_t y = d->output_scanline;
    JSAMPROW rows[1] = {row.data()};
    jpeg_read_scanlines(d, rows, 1);
    for (size_t x = 0; x < row.size(); ++x) out.data[y * row.size() + x] = t8[row[x]];
  }
  jpeg_finish_decompress(d);
  return true;
}
#endif

void decodeJpeg(const uint8_t* p, size_t n, ImageF& out) {
#ifdef CS_HAVE_JPEG
  jpeg_decompress_struct d{};
  JpegError err{};
  d.err = jpeg_std_error(&err.mgr);
  err.mgr.error_exit = onJpegError;
  err.mgr.output_message = [](j_common_ptr) {};  // warnings would only spam stderr
  jpeg_create_decompress(&d);
  const bool ok = decodeJpegRows(&d, p, n, out, &err);
  jpeg_destroy_decompress(&d);
  if (!ok) throw Error(std::string("corrupt JPEG: ") + shown(err.message, 120));
#else
  (void)p, (void)n, (void)out;
  throw Error("JPEG images need libjpeg, which this build was made without (install libjpeg-dev and rebuild)");
#endif
}

}  // namespace

ImageKind imageKind(const std::string& type) {
  std::string t = type;
  for (const char* prefix : {"sensor_msgs/msg/", "sensor_msgs/"})
    if (t.rfind(prefix, 0) == 0) {
      t = t.substr(std::strlen(prefix));
      return t == "Image" ? ImageKind::Raw : t == "CompressedImage" ? ImageKind::Compressed : ImageKind::None;
    }
  return ImageKind::None;
}

int64_t headerStampNs(const uint8_t* p, size_t n, bool cdr) {
  return guarded([&] {
    Fields f(p, n, cdr);
    return f.header();
  });
}

std::string imageEncoding(const uint8_t* p, size_t n, bool cdr, ImageKind kind) {
  return guarded([&] {
    Fields f(p, n, cdr);
    f.header();
    if (kind == ImageKind::Raw) {
      f.u32(), f.u32();
      return f.str();
    }
    return f.str();  // CompressedImage's format: "png", "jpeg", "mono8; png compressed ..."
  });
}

namespace {
bool hasWord(const std::string& format, const char* word) {
  std::string lower = format;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return lower.find(word) != std::string::npos;
}
}  // namespace

bool supportedEncoding(const std::string& encoding, ImageKind kind) {
  if (kind == ImageKind::Raw) return bytesPerPixel(encoding) != 0;
  // compressedDepth (depth PNGs with a header of their own) is not an image we read.
  if (hasWord(encoding, "compresseddepth")) return false;
  return hasWord(encoding, "png") || hasWord(encoding, "jpeg") || hasWord(encoding, "jpg");
}

void decodeImage(const uint8_t* p, size_t n, bool cdr, ImageKind kind, ImageF& out) {
  guarded([&] {
    Fields f(p, n, cdr);
    if (kind == ImageKind::Raw) {
      convertRaw(parseRaw(f), out);
      return 0;
    }
    f.header();
    const std::string format = f.str();
    const auto data = f.bytes();
    // By content, not the format text: drivers write "png", "mono8; png compressed", "jpeg", ...
    if (data.second >= 8 && std::memcmp(data.first, "\x89PNG\r\n\x1a\n", 8) == 0)
      out = decodePngGray(data.first, data.second, "CompressedImage");
    else if (data.second >= 3 && data.first[0] == 0xFF && data.first[1] == 0xD8 && data.first[2] == 0xFF)
      decodeJpeg(data.first, data.second, out);
    else
      throw Error("CompressedImage (format '" + shown(format) + "') holds neither a PNG nor a JPEG image");
    return 0;
  });
}

}  // namespace cs::logio
