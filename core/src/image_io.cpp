// PNG (libpng), OpenEXR, Middlebury .flo, PLY writers and colour maps.
//
// libpng reports errors by longjmp. To keep that well defined in C++, every call
// that may fail runs inside a small function whose only locals are trivially
// destructible; the RAII owners of files and libpng structs live in the callers,
// are constructed before the setjmp, and so are never skipped by the jump.
#include "curvestereo/image_io.hpp"

#include <png.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfTestFile.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>

namespace cs {
namespace {

// No image this library handles comes close; larger headers are corrupt or hostile,
// and checking before allocating keeps a tiny bad file from requesting gigabytes.
constexpr int kMaxImageSide = 32768;

bool plausibleSize(long long width, long long height) {
  return width >= 0 && height >= 0 && width <= kMaxImageSide && height <= kMaxImageSide;
}

std::string quoted(const std::string& path) { return "'" + path + "'"; }

// Third-party messages sometimes span lines; cs::Error promises one.
std::string oneLine(std::string text) {
  std::replace(text.begin(), text.end(), '\n', ' ');
  std::replace(text.begin(), text.end(), '\r', ' ');
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return text;
}

// ---------------------------------------------------------------- plain files

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

FilePtr openForRead(const std::string& path, const char* what) {
  // fopen succeeds on a directory (reads then fail with EISDIR): say what it is.
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw Error(std::string("cannot open ") + what + " " + quoted(path) + ": " + std::strerror(EISDIR));
  FilePtr file(std::fopen(path.c_str(), "rb"));
  if (!file) throw Error(std::string("cannot open ") + what + " " + quoted(path) + ": " + std::strerror(errno));
  return file;
}

FilePtr openForWrite(const std::string& path, const char* what) {
  FilePtr file(std::fopen(path.c_str(), "wb"));
  if (!file) throw Error(std::string("cannot write ") + what + " " + quoted(path) + ": " + std::strerror(errno));
  return file;
}

// fclose can be the first to notice a full disk, so its result matters for writers.
void closeAfterWrite(FilePtr file, const std::string& path, const char* what) {
  const bool failed = std::ferror(file.get()) != 0;
  const int savedErrno = errno;
  const bool closeFailed = std::fclose(file.release()) != 0;
  if (failed || closeFailed) {
    throw Error(std::string("cannot write ") + what + " " + quoted(path) + ": " +
                std::strerror(failed ? savedErrno : errno));
  }
}

void writeAll(std::FILE* file, const void* data, size_t bytes, const std::string& path, const char* what) {
  if (bytes != 0 && std::fwrite(data, 1, bytes, file) != bytes) {
    throw Error(std::string("cannot write ") + what + " " + quoted(path) + ": " + std::strerror(errno));
  }
}

// Little-endian encoding written byte by byte so the formats do not depend on the host.
void appendU32LE(std::vector<uint8_t>& out, uint32_t value) {
  for (int shift = 0; shift < 32; shift += 8) out.push_back(uint8_t(value >> shift));
}

void appendF32LE(std::vector<uint8_t>& out, float value) {
  uint32_t bits;
  std::memcpy(&bits, &value, sizeof bits);
  appendU32LE(out, bits);
}

uint32_t readU32LE(const uint8_t* bytes) {
  return uint32_t(bytes[0]) | uint32_t(bytes[1]) << 8 | uint32_t(bytes[2]) << 16 | uint32_t(bytes[3]) << 24;
}

float readF32LE(const uint8_t* bytes) {
  const uint32_t bits = readU32LE(bytes);
  float value;
  std::memcpy(&value, &bits, sizeof value);
  return value;
}

// ---------------------------------------------------------------- libpng glue

// Lives in the libpng error pointer; trivially destructible on purpose.
struct PngErrorState {
  char message[256];
};

[[noreturn]] void onPngError(png_structp png, png_const_charp message) {
  auto* state = static_cast<PngErrorState*>(png_get_error_ptr(png));
  std::snprintf(state->message, sizeof state->message, "%s", message ? message : "unknown error");
  png_longjmp(png, 1);
}

// Warnings (unknown chunks, odd gamma) do not stop decoding and would only spam stderr.
void onPngWarning(png_structp, png_const_charp) {}

// A libpng read or write struct with its info struct, destroyed together.
class PngHandle {
 public:
  enum Mode { kRead, kWrite };
  PngHandle(Mode mode, PngErrorState* errors) : mode_(mode) {
    png_ = mode == kRead ? png_create_read_struct(PNG_LIBPNG_VER_STRING, errors, onPngError, onPngWarning)
                         : png_create_write_struct(PNG_LIBPNG_VER_STRING, errors, onPngError, onPngWarning);
    if (png_) info_ = png_create_info_struct(png_);
  }
  ~PngHandle() {
    if (mode_ == kRead)
      png_destroy_read_struct(&png_, info_ ? &info_ : nullptr, nullptr);
    else
      png_destroy_write_struct(&png_, info_ ? &info_ : nullptr);
  }
  PngHandle(const PngHandle&) = delete;
  PngHandle& operator=(const PngHandle&) = delete;

  bool valid() const { return png_ && info_; }
  png_structp png() const { return png_; }
  png_infop info() const { return info_; }

 private:
  Mode mode_;
  png_structp png_ = nullptr;
  png_infop info_ = nullptr;
};

// What the decoder delivers after the transforms: 8 or 16 bits, 1 or 3 channels.
struct PngLayout {
  png_uint_32 width = 0;
  png_uint_32 height = 0;
  int bitDepth = 0;
  int channels = 0;
  int passes = 1;
  size_t rowBytes = 0;
};

// The functions below are the only ones that call setjmp. Each returns false when
// libpng jumped back with an error (its text is in the PngErrorState).

bool readPngInfo(png_structp png, png_infop info, std::FILE* file, png_uint_32* width, png_uint_32* height) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_init_io(png, file);
  png_set_sig_bytes(png, 8);  // the caller already consumed the signature
  png_read_info(png, info);
  *width = png_get_image_width(png, info);
  *height = png_get_image_height(png, info);
  return true;
}

// Expands palette and 1/2/4-bit gray to 8 bits and drops alpha (including tRNS,
// which is simply not expanded), so rows hold 1 or 3 channels of 8 or 16 bits.
bool applyGrayTransforms(png_structp png, png_infop info, PngLayout* layout) {
  if (setjmp(png_jmpbuf(png))) return false;
  const int colorType = png_get_color_type(png, info);
  if (colorType == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (colorType == PNG_COLOR_TYPE_GRAY && png_get_bit_depth(png, info) < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (colorType & PNG_COLOR_MASK_ALPHA) png_set_strip_alpha(png);
  layout->passes = png_set_interlace_handling(png);
  png_read_update_info(png, info);
  layout->width = png_get_image_width(png, info);
  layout->height = png_get_image_height(png, info);
  layout->bitDepth = png_get_bit_depth(png, info);
  layout->channels = png_get_channels(png, info);
  layout->rowBytes = png_get_rowbytes(png, info);
  return true;
}

float pngSample(const png_byte* row, size_t index, int bitDepth) {
  if (bitDepth == 16) return float((unsigned(row[2 * index]) << 8 | row[2 * index + 1]) / 65535.0);
  return unitFromByte(row[index]);
}

void convertRowToGray(const png_byte* row, const PngLayout& layout, float* out) {
  const size_t channels = size_t(layout.channels);
  for (size_t x = 0; x < layout.width; ++x) {
    const size_t first = x * channels;
    if (channels < 3) {
      out[x] = pngSample(row, first, layout.bitDepth);
      continue;
    }
    // Rec. 601 luma on the stored (gamma-encoded) values, as most vision code does.
    const double luma = 0.299 * pngSample(row, first, layout.bitDepth) +
                        0.587 * pngSample(row, first + 1, layout.bitDepth) +
                        0.114 * pngSample(row, first + 2, layout.bitDepth);
    out[x] = float(std::min(1.0, luma));
  }
}

// Non-interlaced images stream through one row buffer; interlaced ones need the
// whole image because every pass fills in pixels of rows already seen.
bool decodePngRows(png_structp png, const PngLayout* layout, png_byte* buffer, float* out) {
  if (setjmp(png_jmpbuf(png))) return false;
  const bool interlaced = layout->passes > 1;
  for (int pass = 0; pass < layout->passes; ++pass) {
    for (png_uint_32 y = 0; y < layout->height; ++y) {
      png_byte* row = interlaced ? buffer + size_t(y) * layout->rowBytes : buffer;
      png_read_row(png, row, nullptr);
      if (!interlaced) convertRowToGray(row, *layout, out + size_t(y) * layout->width);
    }
  }
  if (interlaced) {
    for (png_uint_32 y = 0; y < layout->height; ++y)
      convertRowToGray(buffer + size_t(y) * layout->rowBytes, *layout, out + size_t(y) * layout->width);
  }
  png_read_end(png, nullptr);
  return true;
}

bool encodePng(png_structp png, png_infop info, std::FILE* file, int width, int height, int bitDepth, int colorType,
               png_bytepp rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_init_io(png, file);
  png_set_IHDR(png, info, png_uint_32(width), png_uint_32(height), bitDepth, colorType, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  png_write_image(png, rows);
  png_write_end(png, nullptr);
  return true;
}

void requirePngSignature(std::FILE* file, const std::string& path) {
  png_byte signature[8] = {};
  const size_t got = std::fread(signature, 1, sizeof signature, file);
  if (got != sizeof signature || png_sig_cmp(signature, 0, sizeof signature) != 0)
    throw Error(quoted(path) + " is not a PNG file");
}

[[noreturn]] void throwCorruptPng(const std::string& path, std::FILE* file, const PngErrorState& errors) {
  // libpng's stdio reader only says "Read Error"; name the usual cause.
  if (std::feof(file)) throw Error("corrupt PNG " + quoted(path) + ": file is truncated");
  throw Error("corrupt PNG " + quoted(path) + ": " + oneLine(errors.message));
}

// Writes rows of already-encoded big-endian samples.
void writePngBytes(const std::string& path, int width, int height, int bitDepth, int colorType,
                   std::vector<png_byte>& pixels) {
  if (width <= 0 || height <= 0) throw Error("cannot write empty image to " + quoted(path));
  FilePtr file = openForWrite(path, "image");
  PngErrorState errors{};
  PngHandle handle(PngHandle::kWrite, &errors);
  if (!handle.valid()) throw Error("cannot write image " + quoted(path) + ": libpng initialisation failed");
  const size_t rowBytes = pixels.size() / size_t(height);
  std::vector<png_bytep> rows(static_cast<size_t>(height));
  for (size_t y = 0; y < rows.size(); ++y) rows[y] = pixels.data() + y * rowBytes;
  if (!encodePng(handle.png(), handle.info(), file.get(), width, height, bitDepth, colorType, rows.data()))
    throw Error("cannot write image " + quoted(path) + ": " + oneLine(errors.message));
  closeAfterWrite(std::move(file), path, "image");
}

// NaN maps to 0 so a broken pixel cannot turn into full white.
unsigned quantize(float value, unsigned maxCode) {
  if (!(value > 0.f)) return 0;
  if (value >= 1.f) return maxCode;
  return unsigned(std::lround(double(value) * maxCode));
}

// ---------------------------------------------------------------- OpenEXR helpers

// "Y" is the single-channel convention; "R" is what RGB tools write for a scalar.
std::string pickExrChannel(const Imf::ChannelList& channels, const std::string& path) {
  if (channels.findChannel("Y")) return "Y";
  if (channels.findChannel("R")) return "R";
  if (channels.begin() == channels.end()) throw Error("EXR " + quoted(path) + " has no channels");
  return channels.begin().name();
}

// Walks the header of a single-part EXR before OpenEXR sees it. OpenEXR allocates each
// attribute's value at the size the file claims before reading it, so a 100-byte file can
// ask for gigabytes (found by fuzzing); a data window is likewise trusted. Here every
// attribute must fit in the file and the data window must be plausible.
void checkExrHeader(std::FILE* file, const std::string& path) {
  std::error_code ec;
  const auto fileSize = std::filesystem::file_size(path, ec);
  if (ec) throw Error("cannot read EXR " + quoted(path) + ": " + ec.message());
  // Attribute names come from the file: keep control characters out of the one-line message.
  auto corrupt = [&](std::string why) {
    for (char& c : why)
      if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
    return Error("corrupt EXR " + quoted(path) + ": " + why);
  };
  uint8_t head[8];
  if (std::fread(head, 1, sizeof head, file) != sizeof head) throw corrupt("header is incomplete");
  const uint32_t version = readU32LE(head + 4);
  if ((version & 0xff) != 2) throw corrupt("unknown format version " + std::to_string(version & 0xff));
  if (version & 0x1800) throw Error("EXR " + quoted(path) + " is deep or multi-part, which is not supported");
  const size_t maxName = (version & 0x400) ? 255 : 31;
  auto readName = [&](const char* what) {
    std::string name;
    for (int c; (c = std::fgetc(file)) != 0;) {
      if (c == EOF) throw corrupt("header ends inside an attribute " + std::string(what));
      if (name.size() == maxName) throw corrupt(std::string("attribute ") + what + " is too long");
      name.push_back(char(c));
    }
    return name;
  };
  bool sawWindow = false;
  for (;;) {
    const std::string name = readName("name");
    if (name.empty()) break;
    const std::string type = readName("type");
    if (type.empty()) throw corrupt("attribute '" + name + "' has no type");
    uint8_t sizeBytes[4];
    if (std::fread(sizeBytes, 1, 4, file) != 4) throw corrupt("header ends inside attribute '" + name + "'");
    const int32_t size = int32_t(readU32LE(sizeBytes));
    const long position = std::ftell(file);
    if (size < 0 || position < 0 || (unsigned long long)position + (unsigned long long)size > fileSize)
      throw corrupt("attribute '" + name + "' claims " + std::to_string(size) + " bytes, more than the file holds");
    if (name == "dataWindow" && type == "box2i" && size == 16) {
      uint8_t box[16];
      if (std::fread(box, 1, 16, file) != 16) throw corrupt("header ends inside the data window");
      const long long width = (long long)int32_t(readU32LE(box + 8)) - int32_t(readU32LE(box)) + 1;
      const long long height = (long long)int32_t(readU32LE(box + 12)) - int32_t(readU32LE(box + 4)) + 1;
      if (width <= 0 || height <= 0 || !plausibleSize(width, height))
        throw Error("EXR " + quoted(path) + " has an implausible size " + std::to_string(width) + "x" +
                    std::to_string(height));
      sawWindow = true;
    } else if (std::fseek(file, size, SEEK_CUR) != 0) {
      throw corrupt("cannot skip attribute '" + name + "'");
    }
  }
  if (!sawWindow) throw corrupt("no dataWindow attribute");
}

ImageF readExrChannel(const std::string& path) {
  Imf::InputFile file(path.c_str());
  const Imf::Header& header = file.header();
  const Imath::Box2i window = header.dataWindow();
  const long long width = (long long)window.max.x - window.min.x + 1;
  const long long height = (long long)window.max.y - window.min.y + 1;
  if (!plausibleSize(width, height))
    throw Error("EXR " + quoted(path) + " has an implausible size " + std::to_string(width) + "x" +
                std::to_string(height));
  const std::string name = pickExrChannel(header.channels(), path);
  const Imf::Channel& channel = header.channels()[name];
  if (channel.xSampling != 1 || channel.ySampling != 1)
    throw Error("EXR " + quoted(path) + ": channel '" + name + "' is subsampled, which is not supported");

  ImageF image(static_cast<int>(width), static_cast<int>(height));
  Imf::FrameBuffer frame;
  // Slice::Make offsets the base pointer by the data window origin without overflow.
  frame.insert(name, Imf::Slice::Make(Imf::FLOAT, image.data.data(), window));
  file.setFrameBuffer(frame);
  file.readPixels(window.min.y, window.max.y);
  return image;
}

// ---------------------------------------------------------------- colour helpers

struct Rgb {
  float r, g, b;
};

uint32_t packRgb(const Rgb& c) {
  auto channel = [](float v) { return uint32_t(quantize(v, 255)); };
  return channel(c.r) << 16 | channel(c.g) << 8 | channel(c.b);
}

Rgb mix(const Rgb& a, const Rgb& b, float t) {
  return {a.r + (b.r - a.r) * t, a.g + (b.g - a.g) * t, a.b + (b.b - a.b) * t};
}

// Piecewise-linear stand-in for Google's "turbo": dark blue through cyan, green and
// yellow to dark red, with a brightness that rises then falls so both ends stay
// distinguishable from the middle. Stops are evenly spaced over [0, 1].
Rgb turboLike(float t) {
  static const std::array<Rgb, 11> stops = {{{0.19f, 0.07f, 0.23f},
                                             {0.27f, 0.36f, 0.84f},
                                             {0.22f, 0.60f, 0.99f},
                                             {0.10f, 0.81f, 0.85f},
                                             {0.16f, 0.95f, 0.62f},
                                             {0.55f, 0.99f, 0.25f},
                                             {0.86f, 0.88f, 0.21f},
                                             {0.99f, 0.65f, 0.16f},
                                             {0.94f, 0.40f, 0.07f},
                                             {0.78f, 0.18f, 0.02f},
                                             {0.48f, 0.02f, 0.01f}}};
  const float position = std::clamp(t, 0.f, 1.f) * float(stops.size() - 1);
  const size_t below = std::min(size_t(position), stops.size() - 2);
  return mix(stops[below], stops[below + 1], position - float(below));
}

// The Middlebury flow wheel walks red → yellow → green → cyan → blue → magenta → red,
// giving each leg a share of the circle proportional to how many distinguishable
// hues it has (15, 6, 4, 11, 13, 6 steps in Baker et al.'s description).
Rgb flowWheel(float turn) {  // turn in [0, 1)
  struct Leg {
    float share;
    Rgb to;
  };
  static const std::array<Leg, 6> legs = {
      {{15.f, {1, 1, 0}}, {6.f, {0, 1, 0}}, {4.f, {0, 1, 1}}, {11.f, {0, 0, 1}}, {13.f, {1, 0, 1}}, {6.f, {1, 0, 0}}}};
  const float total = 55.f;
  float along = std::clamp(turn, 0.f, 1.f) * total;
  Rgb from{1, 0, 0};
  for (const Leg& leg : legs) {
    if (along <= leg.share) return mix(from, leg.to, along / leg.share);
    along -= leg.share;
    from = leg.to;
  }
  return from;
}

bool knownFlow(const Vec2f& f) {
  return std::isfinite(f.x) && std::isfinite(f.y) && std::fabs(f.x) < 1e9f && std::fabs(f.y) < 1e9f;
}

float largestKnownMagnitude(const FlowImage& flow) {
  float largest = 0.f;
  for (const Vec2f& f : flow.data)
    if (knownFlow(f)) largest = std::max(largest, std::hypot(f.x, f.y));
  return largest;
}

// Hue from direction; small flow fades to white, flow beyond the maximum is dimmed
// rather than saturated so that clipping remains visible.
uint32_t flowColour(const Vec2f& f, float maxMagnitude) {
  const float pi = 3.14159265358979f;
  const float turn = (std::atan2(-f.y, -f.x) / pi + 1.f) * 0.5f;
  Rgb c = flowWheel(turn);
  const float radius = maxMagnitude > 0.f ? std::hypot(f.x, f.y) / maxMagnitude : 0.f;
  if (radius <= 1.f) return packRgb(mix({1, 1, 1}, c, radius));
  return packRgb({c.r * 0.75f, c.g * 0.75f, c.b * 0.75f});
}

}  // namespace

// ==================================================================== PNG

namespace {

// An 8-bit gray image's rows as stored (readPngGray's `bytes`).
bool decodePngBytes(png_structp png, const PngLayout* layout, uint8_t* out) {
  if (setjmp(png_jmpbuf(png))) return false;
  for (png_uint_32 y = 0; y < layout->height; ++y) png_read_row(png, out + size_t(y) * layout->width, nullptr);
  png_read_end(png, nullptr);
  return true;
}

// The PNG in `file` (signature already checked); `name` names it in errors. With `bytes`,
// an 8-bit one-channel non-interlaced file's samples go there and the image returned is empty.
ImageF readPngStream(std::FILE* file, const std::string& name, PngFormat* format, ImageU8* bytes) {
  PngErrorState errors{};
  PngHandle handle(PngHandle::kRead, &errors);
  if (!handle.valid()) throw Error("cannot read PNG " + quoted(name) + ": libpng initialisation failed");

  png_uint_32 width = 0, height = 0;
  if (!readPngInfo(handle.png(), handle.info(), file, &width, &height)) throwCorruptPng(name, file, errors);
  if (width == 0 || height == 0 || !plausibleSize(width, height))
    throw Error("PNG " + quoted(name) + " has an implausible size " + std::to_string(width) + "x" +
                std::to_string(height));

  if (format) {
    const int colorType = png_get_color_type(handle.png(), handle.info());
    format->bitDepth = png_get_bit_depth(handle.png(), handle.info());
    format->colour = (colorType & PNG_COLOR_MASK_COLOR) != 0;
    format->alpha =
        (colorType & PNG_COLOR_MASK_ALPHA) != 0 || png_get_valid(handle.png(), handle.info(), PNG_INFO_tRNS);
  }
  PngLayout layout;
  if (!applyGrayTransforms(handle.png(), handle.info(), &layout)) throwCorruptPng(name, file, errors);
  if (bytes && layout.bitDepth == 8 && layout.channels == 1 && layout.passes == 1) {
    *bytes = ImageU8(static_cast<int>(layout.width), static_cast<int>(layout.height));
    if (!decodePngBytes(handle.png(), &layout, bytes->data.data())) throwCorruptPng(name, file, errors);
    return ImageF();
  }
  ImageF image(static_cast<int>(layout.width), static_cast<int>(layout.height));
  std::vector<png_byte> buffer(layout.passes > 1 ? layout.rowBytes * layout.height : layout.rowBytes);
  if (!decodePngRows(handle.png(), &layout, buffer.data(), image.data.data())) throwCorruptPng(name, file, errors);
  return image;
}

}  // namespace

ImageF readPngGray(const std::string& path, PngFormat* format, ImageU8* bytes) {
  FilePtr file = openForRead(path, "image");
  requirePngSignature(file.get(), path);
  return readPngStream(file.get(), path, format, bytes);
}

ImageF decodePngGray(const uint8_t* data, size_t size, const std::string& name, PngFormat* format) {
  if (size < 8 || png_sig_cmp(data, 0, 8) != 0) throw Error(quoted(name) + " is not a PNG image");
  // A FILE over the bytes, so that the file reader's libpng glue serves both.
  FilePtr file(fmemopen(const_cast<uint8_t*>(data), size, "rb"));
  if (!file) throw Error("cannot read PNG " + quoted(name) + ": " + std::strerror(errno));
  std::fseek(file.get(), 8, SEEK_SET);
  return readPngStream(file.get(), name, format, nullptr);
}

void writePngGray(const std::string& path, const ImageF& img) {
  std::vector<png_byte> pixels(img.size());
  for (size_t i = 0; i < img.size(); ++i) pixels[i] = png_byte(quantize(img.data[i], 255));
  writePngBytes(path, img.width, img.height, 8, PNG_COLOR_TYPE_GRAY, pixels);
}

void writePngGray16(const std::string& path, const ImageF& img) {
  std::vector<png_byte> pixels(2 * img.size());
  for (size_t i = 0; i < img.size(); ++i) {
    const unsigned code = quantize(img.data[i], 65535);
    pixels[2 * i] = png_byte(code >> 8);  // PNG stores 16-bit samples big-endian
    pixels[2 * i + 1] = png_byte(code & 0xff);
  }
  writePngBytes(path, img.width, img.height, 16, PNG_COLOR_TYPE_GRAY, pixels);
}

void writePngRgb(const std::string& path, const Image<uint32_t>& rgb) {
  std::vector<png_byte> pixels(3 * rgb.size());
  for (size_t i = 0; i < rgb.size(); ++i) {
    pixels[3 * i] = png_byte(rgb.data[i] >> 16);
    pixels[3 * i + 1] = png_byte(rgb.data[i] >> 8);
    pixels[3 * i + 2] = png_byte(rgb.data[i]);
  }
  writePngBytes(path, rgb.width, rgb.height, 8, PNG_COLOR_TYPE_RGB, pixels);
}

// ==================================================================== OpenEXR

ImageF readExr(const std::string& path) {
  FilePtr file = openForRead(path, "image");  // a clear errno message before OpenEXR's own wording
  if (!Imf::isOpenExrFile(path.c_str())) throw Error(quoted(path) + " is not an OpenEXR file");
  checkExrHeader(file.get(), path);
  file.reset();
  try {
    return readExrChannel(path);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error("corrupt EXR " + quoted(path) + ": " + oneLine(e.what()));
  }
}

void writeExr(const std::string& path, const ImageF& img) {
  if (img.width <= 0 || img.height <= 0) throw Error("cannot write empty image to " + quoted(path));
  try {
    Imf::Header header(img.width, img.height);
    header.compression() = Imf::ZIP_COMPRESSION;
    header.channels().insert("Y", Imf::Channel(Imf::FLOAT));
    Imf::OutputFile file(path.c_str(), header);
    Imf::FrameBuffer frame;
    // OpenEXR's Slice wants a mutable pointer even for writing; it only reads.
    frame.insert("Y", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(img.data.data())),
                                 sizeof(float), sizeof(float) * size_t(img.width)));
    file.setFrameBuffer(frame);
    file.writePixels(img.height);
  } catch (const std::exception& e) {
    throw Error("cannot write EXR " + quoted(path) + ": " + oneLine(e.what()));
  }
}

// ==================================================================== Middlebury .flo

FlowImage readFlo(const std::string& path) {
  FilePtr file = openForRead(path, "flow file");
  uint8_t header[12];
  if (std::fread(header, 1, sizeof header, file.get()) != sizeof header)
    throw Error("truncated .flo " + quoted(path) + ": header is incomplete");
  if (std::memcmp(header, "PIEH", 4) != 0)  // the bytes of 202021.25f, little-endian
    throw Error(quoted(path) + " is not a .flo file (bad magic number)");
  const int32_t width = int32_t(readU32LE(header + 4));
  const int32_t height = int32_t(readU32LE(header + 8));
  if (!plausibleSize(width, height))
    throw Error(".flo " + quoted(path) + " has an implausible size " + std::to_string(width) + "x" +
                std::to_string(height));

  // Compare with the real file size before allocating, so a lying header costs nothing.
  const size_t expected = sizeof header + size_t(width) * size_t(height) * 8;
  std::error_code ec;
  const auto actual = std::filesystem::file_size(path, ec);
  if (!ec && actual < expected)
    throw Error("truncated .flo " + quoted(path) + ": expected " + std::to_string(expected) + " bytes, found " +
                std::to_string(actual));

  std::vector<uint8_t> bytes(expected - sizeof header);
  if (std::fread(bytes.data(), 1, bytes.size(), file.get()) != bytes.size())
    throw Error("truncated .flo " + quoted(path) + ": flow data ends early");
  FlowImage flow(width, height);
  for (size_t i = 0; i < flow.size(); ++i) flow.data[i] = {readF32LE(&bytes[8 * i]), readF32LE(&bytes[8 * i + 4])};
  return flow;
}

void writeFlo(const std::string& path, const FlowImage& flow) {
  auto encode = [](float v) { return std::isfinite(v) && std::fabs(v) < 1e9f ? v : kFloUnknown; };
  std::vector<uint8_t> bytes{'P', 'I', 'E', 'H'};
  bytes.reserve(12 + 8 * flow.size());
  appendU32LE(bytes, uint32_t(flow.width));
  appendU32LE(bytes, uint32_t(flow.height));
  for (const Vec2f& f : flow.data) {
    appendF32LE(bytes, encode(f.x));
    appendF32LE(bytes, encode(f.y));
  }
  FilePtr file = openForWrite(path, "flow file");
  writeAll(file.get(), bytes.data(), bytes.size(), path, "flow file");
  closeAfterWrite(std::move(file), path, "flow file");
}

// ==================================================================== PLY

void writePly(const std::string& path, const std::vector<PlyPoint>& points) {
  // Gray is stored as red = green = blue: viewers understand colour, not "gray".
  const std::string header = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(points.size()) +
                             "\nproperty float x\nproperty float y\nproperty float z\n"
                             "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
  std::vector<uint8_t> bytes(header.begin(), header.end());
  bytes.reserve(header.size() + 15 * points.size());
  for (const PlyPoint& p : points) {
    appendF32LE(bytes, p.x);
    appendF32LE(bytes, p.y);
    appendF32LE(bytes, p.z);
    bytes.insert(bytes.end(), 3, p.gray);
  }
  FilePtr file = openForWrite(path, "point cloud");
  writeAll(file.get(), bytes.data(), bytes.size(), path, "point cloud");
  closeAfterWrite(std::move(file), path, "point cloud");
}

// ==================================================================== colour maps

Image<uint32_t> colorizeScalar(const ImageF& values, float lo, float hi) {
  Image<uint32_t> out(values.width, values.height, 0);
  const float span = hi - lo;
  // hi < lo is allowed and reverses the map (handy for "near is red" on inverse depth).
  const bool usableRange = std::isfinite(lo) && std::isfinite(span) && span != 0.f;
  for (size_t i = 0; i < values.size(); ++i) {
    const float v = values.data[i];
    if (!std::isfinite(v)) continue;  // stays black
    out.data[i] = packRgb(turboLike(usableRange ? (v - lo) / span : 0.f));
  }
  return out;
}

Image<uint32_t> depthPicture(const ImageF& radialDepth) {
  ImageF inverse(radialDepth.width, radialDepth.height, NAN);
  std::vector<float> finite;
  for (size_t i = 0; i < inverse.size(); ++i) {
    const float d = radialDepth.data[i];
    if (std::isnan(d) || d <= 0) continue;
    inverse.data[i] = std::isinf(d) ? 0.f : 1.f / d;
    finite.push_back(inverse.data[i]);
  }
  float lo = 0.f, hi = 1.f;
  if (!finite.empty()) {
    std::sort(finite.begin(), finite.end());
    lo = finite[size_t(0.02 * double(finite.size() - 1))];
    hi = finite[size_t(0.98 * double(finite.size() - 1))];
    if (hi <= lo) hi = lo + 1e-3f;
  }
  return colorizeScalar(inverse, lo, hi);
}

// maxMagnitude <= 0 (or non-finite) means "scale by the largest known flow".
Image<uint32_t> colorizeFlow(const FlowImage& flow, float maxMagnitude) {
  if (!(maxMagnitude > 0.f) || !std::isfinite(maxMagnitude)) maxMagnitude = largestKnownMagnitude(flow);
  Image<uint32_t> out(flow.width, flow.height, 0);
  for (size_t i = 0; i < flow.size(); ++i)
    if (knownFlow(flow.data[i])) out.data[i] = flowColour(flow.data[i], maxMagnitude);
  return out;
}

}  // namespace cs
