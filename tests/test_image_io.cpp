// Tests for the file formats in image_io.hpp: PNG, OpenEXR, .flo, PLY, colour maps.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include "curvestereo/image_io.hpp"
#include "test_util.hpp"

namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<unsigned char>;

// Small PNGs made once with libpng's writer, embedded so that the reader is tested
// on layouts writePng* never produces (palette, alpha, low bit depths, Adam7).
const unsigned char kPalette4x1[] = {
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52, 0x00, 0x00,
    0x00, 0x04, 0x00, 0x00, 0x00, 0x01, 0x08, 0x03, 0x00, 0x00, 0x00, 0xce, 0xe2, 0xff, 0xff, 0x00, 0x00, 0x00,
    0x0c, 0x50, 0x4c, 0x54, 0x45, 0xff, 0x00, 0x00, 0x00, 0xff, 0x00, 0x00, 0x00, 0xff, 0xff, 0xff, 0xff, 0xfb,
    0x00, 0x60, 0xf6, 0x00, 0x00, 0x00, 0x01, 0x74, 0x52, 0x4e, 0x53, 0x80, 0xad, 0x5e, 0x5b, 0x46, 0x00, 0x00,
    0x00, 0x0d, 0x49, 0x44, 0x41, 0x54, 0x08, 0xd7, 0x63, 0x60, 0x60, 0x64, 0x62, 0x06, 0x00, 0x00, 0x0f, 0x00,
    0x07, 0x7f, 0x8b, 0xf6, 0x17, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82,
};
const unsigned char kGrayAlpha2x1[] = {
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52, 0x00, 0x00,
    0x00, 0x02, 0x00, 0x00, 0x00, 0x01, 0x08, 0x04, 0x00, 0x00, 0x00, 0x5e, 0x2b, 0xb7, 0x01, 0x00, 0x00, 0x00,
    0x0d, 0x49, 0x44, 0x41, 0x54, 0x08, 0xd7, 0x63, 0x60, 0xf8, 0xff, 0x9f, 0x01, 0x00, 0x05, 0x00, 0x01, 0xff,
    0xf2, 0x7f, 0x29, 0x57, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82,
};
const unsigned char kGray1Bit9x1[] = {
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52, 0x00,
    0x00, 0x00, 0x09, 0x00, 0x00, 0x00, 0x01, 0x01, 0x00, 0x00, 0x00, 0x00, 0x24, 0xb9, 0xb9, 0xd0, 0x00,
    0x00, 0x00, 0x0b, 0x49, 0x44, 0x41, 0x54, 0x08, 0xd7, 0x63, 0xd8, 0xd4, 0x00, 0x00, 0x01, 0xe7, 0x01,
    0x33, 0x36, 0x67, 0x4d, 0xbe, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82,
};
const unsigned char kGray2Bit4x1[] = {
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52, 0x00,
    0x00, 0x00, 0x04, 0x00, 0x00, 0x00, 0x01, 0x02, 0x00, 0x00, 0x00, 0x00, 0x96, 0xe7, 0x48, 0xb0, 0x00,
    0x00, 0x00, 0x0a, 0x49, 0x44, 0x41, 0x54, 0x08, 0xd7, 0x63, 0x90, 0x06, 0x00, 0x00, 0x1d, 0x00, 0x1c,
    0x24, 0x7a, 0xed, 0x63, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82,
};
const unsigned char kInterlaced9x9[] = {
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52, 0x00, 0x00,
    0x00, 0x09, 0x00, 0x00, 0x00, 0x09, 0x08, 0x00, 0x00, 0x00, 0x01, 0xb2, 0xfd, 0x69, 0x5a, 0x00, 0x00, 0x00,
    0x42, 0x49, 0x44, 0x41, 0x54, 0x08, 0xd7, 0x63, 0x60, 0x90, 0x60, 0xb8, 0xf1, 0x81, 0x81, 0x87, 0xe1, 0x09,
    0x63, 0x0e, 0x0f, 0x0f, 0x23, 0x1b, 0x0f, 0x4b, 0x0e, 0x0f, 0xe3, 0x3d, 0x1e, 0x46, 0x33, 0x36, 0x36, 0x36,
    0x36, 0xc6, 0x45, 0x6c, 0x6c, 0x6c, 0x6c, 0x8c, 0xcc, 0x6c, 0x6c, 0x6c, 0x2c, 0x66, 0x28, 0x04, 0xe3, 0x6d,
    0x36, 0x36, 0x36, 0x46, 0x69, 0x66, 0x28, 0x60, 0x31, 0xc3, 0xc7, 0x02, 0x00, 0x6e, 0x37, 0x08, 0xec, 0xa3,
    0x28, 0xf7, 0x71, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82,
};
const unsigned char kRgba16Bit2x1[] = {
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52, 0x00, 0x00, 0x00,
    0x02, 0x00, 0x00, 0x00, 0x01, 0x10, 0x06, 0x00, 0x00, 0x00, 0xa4, 0xb2, 0xa3, 0xc9, 0x00, 0x00, 0x00, 0x12, 0x49,
    0x44, 0x41, 0x54, 0x08, 0xd7, 0x63, 0xf8, 0xff, 0x9f, 0x01, 0x0e, 0xfe, 0xff, 0xff, 0xff, 0x1f, 0x00, 0x28, 0xe8,
    0x05, 0xfb, 0xcc, 0x34, 0xae, 0xdf, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82,
};

// A 10x10 display window holding a 3x2 data window at (5,7), HALF channels G and R
// (R = 0, 0.5, 1, 1.5, 2, 2.5; G = -1), no compression, made with OpenEXR.
const unsigned char kWindowedExr[] = {
    0x76, 0x2f, 0x31, 0x01, 0x02, 0x00, 0x00, 0x00, 0x63, 0x68, 0x61, 0x6e, 0x6e, 0x65, 0x6c, 0x73, 0x00, 0x63, 0x68,
    0x6c, 0x69, 0x73, 0x74, 0x00, 0x25, 0x00, 0x00, 0x00, 0x47, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
    0x01, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x52, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x01,
    0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x63, 0x6f, 0x6d, 0x70, 0x72, 0x65, 0x73, 0x73, 0x69, 0x6f, 0x6e,
    0x00, 0x63, 0x6f, 0x6d, 0x70, 0x72, 0x65, 0x73, 0x73, 0x69, 0x6f, 0x6e, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x64,
    0x61, 0x74, 0x61, 0x57, 0x69, 0x6e, 0x64, 0x6f, 0x77, 0x00, 0x62, 0x6f, 0x78, 0x32, 0x69, 0x00, 0x10, 0x00, 0x00,
    0x00, 0x05, 0x00, 0x00, 0x00, 0x07, 0x00, 0x00, 0x00, 0x07, 0x00, 0x00, 0x00, 0x08, 0x00, 0x00, 0x00, 0x64, 0x69,
    0x73, 0x70, 0x6c, 0x61, 0x79, 0x57, 0x69, 0x6e, 0x64, 0x6f, 0x77, 0x00, 0x62, 0x6f, 0x78, 0x32, 0x69, 0x00, 0x10,
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x09, 0x00, 0x00, 0x00, 0x09, 0x00, 0x00, 0x00,
    0x6c, 0x69, 0x6e, 0x65, 0x4f, 0x72, 0x64, 0x65, 0x72, 0x00, 0x6c, 0x69, 0x6e, 0x65, 0x4f, 0x72, 0x64, 0x65, 0x72,
    0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x70, 0x69, 0x78, 0x65, 0x6c, 0x41, 0x73, 0x70, 0x65, 0x63, 0x74, 0x52, 0x61,
    0x74, 0x69, 0x6f, 0x00, 0x66, 0x6c, 0x6f, 0x61, 0x74, 0x00, 0x04, 0x00, 0x00, 0x00, 0x00, 0x00, 0x80, 0x3f, 0x73,
    0x63, 0x72, 0x65, 0x65, 0x6e, 0x57, 0x69, 0x6e, 0x64, 0x6f, 0x77, 0x43, 0x65, 0x6e, 0x74, 0x65, 0x72, 0x00, 0x76,
    0x32, 0x66, 0x00, 0x08, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x73, 0x63, 0x72, 0x65,
    0x65, 0x6e, 0x57, 0x69, 0x6e, 0x64, 0x6f, 0x77, 0x57, 0x69, 0x64, 0x74, 0x68, 0x00, 0x66, 0x6c, 0x6f, 0x61, 0x74,
    0x00, 0x04, 0x00, 0x00, 0x00, 0x00, 0x00, 0x80, 0x3f, 0x00, 0x37, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x4b,
    0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x07, 0x00, 0x00, 0x00, 0x0c, 0x00, 0x00, 0x00, 0x00, 0xbc, 0x00, 0xbc,
    0x00, 0xbc, 0x00, 0x00, 0x00, 0x38, 0x00, 0x3c, 0x08, 0x00, 0x00, 0x00, 0x0c, 0x00, 0x00, 0x00, 0x00, 0xbc, 0x00,
    0xbc, 0x00, 0xbc, 0x00, 0x3e, 0x00, 0x40, 0x00, 0x41,
};

Bytes readBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), {});
}

void writeBytes(const fs::path& path, const unsigned char* data, size_t size) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
}

void writeBytes(const fs::path& path, const Bytes& bytes) { writeBytes(path, bytes.data(), bytes.size()); }

void writeText(const fs::path& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

// Keeps the first half of a file: the typical result of an interrupted download.
void truncateToHalf(const fs::path& path) {
  Bytes bytes = readBytes(path);
  bytes.resize(bytes.size() / 2);
  writeBytes(path, bytes);
}

// The message of the cs::Error thrown by f, or "" when it throws nothing.
template <class F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const cs::Error& e) {
    return e.what();
  }
  return "";
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

float luma(uint32_t rgb) {
  return (0.299f * float((rgb >> 16) & 0xff) + 0.587f * float((rgb >> 8) & 0xff) + 0.114f * float(rgb & 0xff)) / 255.f;
}

cs::ImageF ramp(int width, int height) {
  cs::ImageF img(width, height);
  for (size_t i = 0; i < img.size(); ++i) img.data[i] = float(i) / float(img.size() - 1);
  return img;
}

cs::ImageF readEmbeddedPng(const std::string& name, const unsigned char* data, size_t size) {
  const fs::path path = cs::test::tempDir("io_embedded") / (name + ".png");
  writeBytes(path, data, size);
  return cs::readPngGray(path.string());
}

// Bitwise equality, so that NaN == NaN and -0 != +0.
bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Big-endian CRC-32 as PNG chunks need it (bitwise form; speed is irrelevant here).
uint32_t crc32(const Bytes& bytes) {
  uint32_t crc = 0xffffffffu;
  for (unsigned char byte : bytes) {
    crc ^= byte;
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

void appendBE32(Bytes& out, uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back((unsigned char)(v >> shift));
}

// Appends length, type + data, CRC: one PNG chunk.
void appendChunk(Bytes& png, const Bytes& typeAndData) {
  appendBE32(png, uint32_t(typeAndData.size() - 4));
  png.insert(png.end(), typeAndData.begin(), typeAndData.end());
  appendBE32(png, crc32(typeAndData));
}

// A structurally valid PNG that claims the given size but carries almost no pixels.
Bytes pngHeaderClaiming(uint32_t width, uint32_t height) {
  Bytes png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  Bytes header = {'I', 'H', 'D', 'R'};
  appendBE32(header, width);
  appendBE32(header, height);
  header.insert(header.end(), {8, 0, 0, 0, 0});  // 8-bit gray, no interlace
  appendChunk(png, header);
  appendChunk(png, {'I', 'D', 'A', 'T', 0x78, 0x9c});
  appendChunk(png, {'I', 'E', 'N', 'D'});
  return png;
}

Bytes floHeader(const char magic[4], int32_t width, int32_t height) {
  Bytes bytes(magic, magic + 4);
  for (int32_t v : {width, height})
    for (int shift = 0; shift < 32; shift += 8) bytes.push_back((unsigned char)(uint32_t(v) >> shift));
  return bytes;
}

}  // namespace

// ------------------------------------------------------------------ PNG

TEST_CASE("PNG 8-bit gray round trip") {
  const fs::path path = cs::test::tempDir("io_png8") / "gray.png";
  cs::ImageF img = ramp(37, 23);
  cs::writePngGray(path.string(), img);
  const cs::ImageF back = cs::readPngGray(path.string());
  REQUIRE(back.width == 37);
  REQUIRE(back.height == 23);
  for (size_t i = 0; i < img.size(); ++i) CHECK(std::fabs(back.data[i] - img.data[i]) <= 1.f / 255.f);
}

TEST_CASE("PNG writer clamps out-of-range and NaN values") {
  const fs::path path = cs::test::tempDir("io_png_clamp") / "clamp.png";
  cs::ImageF img(3, 1);
  img.data = {-0.5f, 1.5f, std::numeric_limits<float>::quiet_NaN()};
  cs::writePngGray(path.string(), img);
  const cs::ImageF back = cs::readPngGray(path.string());
  CHECK(back.data[0] == 0.f);
  CHECK(back.data[1] == 1.f);
  CHECK(back.data[2] == 0.f);
}

TEST_CASE("PNG 16-bit gray round trip") {
  const fs::path path = cs::test::tempDir("io_png16") / "gray16.png";
  cs::ImageF img = ramp(300, 7);
  cs::writePngGray16(path.string(), img);
  const cs::ImageF back = cs::readPngGray(path.string());
  REQUIRE(back.width == 300);
  REQUIRE(back.height == 7);
  for (size_t i = 0; i < img.size(); ++i) CHECK(std::fabs(back.data[i] - img.data[i]) <= 1.f / 65535.f);
}

TEST_CASE("PNG colour is read as Rec. 601 luma") {
  const fs::path path = cs::test::tempDir("io_png_rgb") / "rgb.png";
  cs::Image<uint32_t> rgb(6, 1);
  rgb.data = {0xff0000, 0x00ff00, 0x0000ff, 0xffffff, 0x000000, 0x3c7fd2};
  cs::writePngRgb(path.string(), rgb);
  const cs::ImageF back = cs::readPngGray(path.string());
  REQUIRE(back.width == 6);
  for (size_t i = 0; i < rgb.size(); ++i) CHECK(back.data[i] == doctest::Approx(luma(rgb.data[i])).epsilon(1e-5));
  CHECK(back.data[3] <= 1.f);
}

TEST_CASE("PNG reader expands palette, alpha, low bit depths and interlacing") {
  SUBCASE("palette with tRNS") {
    const cs::ImageF img = readEmbeddedPng("palette", kPalette4x1, sizeof kPalette4x1);
    REQUIRE(img.width == 4);
    CHECK(img.data[0] == doctest::Approx(0.299f));
    CHECK(img.data[1] == doctest::Approx(0.587f));
    CHECK(img.data[2] == doctest::Approx(0.114f));
    CHECK(img.data[3] == doctest::Approx(1.f));
  }
  SUBCASE("gray + alpha drops alpha") {
    const cs::ImageF img = readEmbeddedPng("gray_alpha", kGrayAlpha2x1, sizeof kGrayAlpha2x1);
    REQUIRE(img.width == 2);
    CHECK(img.data[0] == 0.f);
    CHECK(img.data[1] == 1.f);
  }
  SUBCASE("1-bit gray") {
    const cs::ImageF img = readEmbeddedPng("gray1", kGray1Bit9x1, sizeof kGray1Bit9x1);
    REQUIRE(img.width == 9);
    const float expected[9] = {1, 0, 1, 1, 0, 0, 1, 0, 1};
    for (int x = 0; x < 9; ++x) CHECK(img(x, 0) == expected[x]);
  }
  SUBCASE("2-bit gray") {
    const cs::ImageF img = readEmbeddedPng("gray2", kGray2Bit4x1, sizeof kGray2Bit4x1);
    REQUIRE(img.width == 4);
    for (int x = 0; x < 4; ++x) CHECK(img(x, 0) == doctest::Approx(x / 3.0));
  }
  SUBCASE("Adam7 interlaced") {
    const cs::ImageF img = readEmbeddedPng("interlaced", kInterlaced9x9, sizeof kInterlaced9x9);
    REQUIRE(img.width == 9);
    REQUIRE(img.height == 9);
    for (int y = 0; y < 9; ++y)
      for (int x = 0; x < 9; ++x) CHECK(img(x, y) == doctest::Approx((x + 9 * y) * 3 / 255.0));
  }
  SUBCASE("16-bit RGBA") {
    const cs::ImageF img = readEmbeddedPng("rgba16", kRgba16Bit2x1, sizeof kRgba16Bit2x1);
    REQUIRE(img.width == 2);
    CHECK(img.data[0] == doctest::Approx(0.299f));
    CHECK(img.data[1] == doctest::Approx(0.114f));
  }
}

TEST_CASE("PNG errors name the file") {
  const fs::path dir = cs::test::tempDir("io_png_errors");

  SUBCASE("missing file") {
    const std::string path = (dir / "missing.png").string();
    const std::string message = errorOf([&] { cs::readPngGray(path); });
    CHECK(message == "cannot open image '" + path + "': No such file or directory");
  }
  SUBCASE("not a PNG") {
    const std::string path = (dir / "text.png").string();
    writeText(path, "this is plain text, not an image\n");
    CHECK(errorOf([&] { cs::readPngGray(path); }) == "'" + path + "' is not a PNG file");
  }
  SUBCASE("empty file") {
    const std::string path = (dir / "empty.png").string();
    writeText(path, "");
    CHECK(contains(errorOf([&] { cs::readPngGray(path); }), "is not a PNG file"));
  }
  SUBCASE("truncated PNG") {
    const fs::path path = dir / "truncated.png";
    cs::ImageF noise(64, 64);
    for (size_t i = 0; i < noise.size(); ++i) noise.data[i] = float((i * 7919) % 251) / 250.f;
    cs::writePngGray(path.string(), noise);
    truncateToHalf(path);
    const std::string message = errorOf([&] { cs::readPngGray(path.string()); });
    CHECK(contains(message, "corrupt PNG '" + path.string() + "'"));
    CHECK(!contains(message, "\n"));
  }
  SUBCASE("header chunk cut short") {
    const fs::path path = dir / "signature.png";
    writeBytes(path, pngHeaderClaiming(4, 4));
    truncateToHalf(path);  // cuts into the IHDR chunk
    CHECK(contains(errorOf([&] { cs::readPngGray(path.string()); }), "corrupt PNG"));
  }
  SUBCASE("absurd size is rejected before decoding") {
    const fs::path path = dir / "huge.png";
    writeBytes(path, pngHeaderClaiming(40000, 40000));
    const std::string message = errorOf([&] { cs::readPngGray(path.string()); });
    CHECK(contains(message, path.string()));
    CHECK(contains(message, "40000x40000"));
  }
  SUBCASE("unwritable destination") {
    const std::string path = (dir / "no_such_dir" / "out.png").string();
    CHECK(contains(errorOf([&] { cs::writePngGray(path, cs::ImageF(2, 2)); }), "cannot write image"));
    CHECK(contains(errorOf([&] { cs::writePngGray((dir / "empty_out.png").string(), cs::ImageF()); }), "empty"));
  }
}

// ------------------------------------------------------------------ OpenEXR

TEST_CASE("EXR round trip is exact, including inf and NaN") {
  const fs::path path = cs::test::tempDir("io_exr") / "depth.exr";
  cs::ImageF img = ramp(41, 17);
  const float inf = std::numeric_limits<float>::infinity();
  img(0, 0) = inf;
  img(1, 0) = -inf;
  img(2, 0) = std::numeric_limits<float>::quiet_NaN();
  img(3, 0) = std::numeric_limits<float>::denorm_min();
  img(4, 0) = -0.f;
  img(5, 0) = 1e30f;
  img(40, 16) = 123456.789f;
  cs::writeExr(path.string(), img);
  const cs::ImageF back = cs::readExr(path.string());
  REQUIRE(back.width == 41);
  REQUIRE(back.height == 17);
  for (size_t i = 0; i < img.size(); ++i) CHECK(sameBits(back.data[i], img.data[i]));
}

TEST_CASE("EXR reader handles an offset data window and picks channel R without Y") {
  const fs::path path = cs::test::tempDir("io_exr_window") / "window.exr";
  writeBytes(path, kWindowedExr, sizeof kWindowedExr);
  const cs::ImageF img = cs::readExr(path.string());
  REQUIRE(img.width == 3);
  REQUIRE(img.height == 2);
  for (size_t i = 0; i < img.size(); ++i) CHECK(img.data[i] == 0.5f * float(i));  // HALF → float exactly
}

TEST_CASE("EXR errors name the file") {
  const fs::path dir = cs::test::tempDir("io_exr_errors");

  SUBCASE("missing file") {
    const std::string path = (dir / "missing.exr").string();
    CHECK(errorOf([&] { cs::readExr(path); }) == "cannot open image '" + path + "': No such file or directory");
  }
  SUBCASE("not an EXR") {
    const std::string path = (dir / "text.exr").string();
    writeText(path, "definitely not OpenEXR\n");
    CHECK(errorOf([&] { cs::readExr(path); }) == "'" + path + "' is not an OpenEXR file");
  }
  SUBCASE("truncated EXR") {
    const fs::path path = dir / "truncated.exr";
    cs::ImageF noise(200, 100);
    for (size_t i = 0; i < noise.size(); ++i) noise.data[i] = float((i * 7919) % 1009);
    cs::writeExr(path.string(), noise);
    truncateToHalf(path);
    const std::string message = errorOf([&] { cs::readExr(path.string()); });
    CHECK(contains(message, "corrupt EXR '" + path.string() + "'"));
    CHECK(!contains(message, "\n"));
  }
  SUBCASE("unwritable destination") {
    const std::string path = (dir / "no_such_dir" / "out.exr").string();
    CHECK(contains(errorOf([&] { cs::writeExr(path, cs::ImageF(2, 2)); }), "cannot write EXR '" + path + "'"));
  }
}

// ------------------------------------------------------------------ .flo

TEST_CASE(".flo round trip, with unknown components written as kFloUnknown") {
  const fs::path path = cs::test::tempDir("io_flo") / "flow.flo";
  cs::FlowImage flow(5, 3);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 5; ++x) flow(x, y) = {0.25f * float(x) - 1.f, -3.5f * float(y) + 0.125f};
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  flow(0, 0) = {nan, 1.f};
  flow(1, 0) = {2.f, -inf};
  flow(2, 0) = {3e9f, 4.f};  // already "unknown" by the |v| >= 1e9 rule
  cs::writeFlo(path.string(), flow);
  CHECK(fs::file_size(path) == 12u + 5u * 3u * 8u);

  const cs::FlowImage back = cs::readFlo(path.string());
  REQUIRE(back.width == 5);
  REQUIRE(back.height == 3);
  CHECK(back(0, 0).x == cs::kFloUnknown);
  CHECK(back(0, 0).y == 1.f);
  CHECK(back(1, 0).x == 2.f);
  CHECK(back(1, 0).y == cs::kFloUnknown);
  CHECK(back(2, 0).x == cs::kFloUnknown);
  for (size_t i = 3; i < flow.size(); ++i) {
    CHECK(back.data[i].x == flow.data[i].x);
    CHECK(back.data[i].y == flow.data[i].y);
  }
  // The magic number is the float 202021.25 stored little-endian.
  const Bytes bytes = readBytes(path);
  float magic;
  std::memcpy(&magic, bytes.data(), sizeof magic);
  CHECK(magic == 202021.25f);
}

TEST_CASE(".flo errors name the file") {
  const fs::path dir = cs::test::tempDir("io_flo_errors");

  SUBCASE("missing file") {
    CHECK(contains(errorOf([&] { cs::readFlo((dir / "missing.flo").string()); }), "No such file or directory"));
  }
  SUBCASE("truncated data") {
    const fs::path path = dir / "truncated.flo";
    cs::writeFlo(path.string(), cs::FlowImage(20, 10));
    truncateToHalf(path);
    const std::string message = errorOf([&] { cs::readFlo(path.string()); });
    CHECK(contains(message, "truncated .flo '" + path.string() + "'"));
  }
  SUBCASE("truncated header") {
    const fs::path path = dir / "short.flo";
    writeText(path, "PIEH");
    CHECK(contains(errorOf([&] { cs::readFlo(path.string()); }), "truncated"));
  }
  SUBCASE("bad magic") {
    const fs::path path = dir / "magic.flo";
    Bytes bytes = floHeader("HEIP", 1, 1);
    bytes.resize(bytes.size() + 8, 0);
    writeBytes(path, bytes);
    CHECK(contains(errorOf([&] { cs::readFlo(path.string()); }), "bad magic"));
  }
  SUBCASE("negative and absurd sizes") {
    const fs::path path = dir / "size.flo";
    writeBytes(path, floHeader("PIEH", -4, 3));
    CHECK(contains(errorOf([&] { cs::readFlo(path.string()); }), "-4x3"));
    writeBytes(path, floHeader("PIEH", 100000, 100000));
    CHECK(contains(errorOf([&] { cs::readFlo(path.string()); }), "implausible size"));
  }
}

// ------------------------------------------------------------------ PLY

TEST_CASE("PLY header and payload size") {
  const fs::path path = cs::test::tempDir("io_ply") / "cloud.ply";
  std::vector<cs::PlyPoint> points = {{1.f, 2.f, 3.f, 10}, {-1.f, 0.5f, 7.f, 200}, {0.f, 0.f, 0.f, 255}};
  cs::writePly(path.string(), points);

  const Bytes bytes = readBytes(path);
  const std::string text(bytes.begin(), bytes.end());
  const std::string endHeader = "end_header\n";
  const size_t headerEnd = text.find(endHeader);
  REQUIRE(headerEnd != std::string::npos);
  const std::string header = text.substr(0, headerEnd + endHeader.size());
  CHECK(header.rfind("ply\nformat binary_little_endian 1.0\n", 0) == 0);
  CHECK(contains(header, "element vertex 3\n"));
  for (const char* property : {"property float x\n", "property float y\n", "property float z\n", "property uchar red\n",
                               "property uchar green\n", "property uchar blue\n"})
    CHECK(contains(header, property));
  CHECK(bytes.size() == header.size() + points.size() * 15);

  // Second vertex: x, y, z floats then gray replicated into r, g, b.
  const unsigned char* vertex = bytes.data() + header.size() + 15;
  float xyz[3];
  std::memcpy(xyz, vertex, sizeof xyz);
  CHECK(xyz[0] == -1.f);
  CHECK(xyz[1] == 0.5f);
  CHECK(xyz[2] == 7.f);
  CHECK(vertex[12] == 200);
  CHECK(vertex[13] == 200);
  CHECK(vertex[14] == 200);
}

// ------------------------------------------------------------------ colour maps

TEST_CASE("colorizeScalar: ends differ, middle is bright, non-finite is black") {
  cs::ImageF values(5, 1);
  values.data = {0.f, 0.5f, 1.f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()};
  const cs::Image<uint32_t> rgb = cs::colorizeScalar(values, 0.f, 1.f);
  REQUIRE(rgb.width == 5);
  const uint32_t low = rgb.data[0], mid = rgb.data[1], high = rgb.data[2];
  CHECK((low & 0xff) > ((low >> 16) & 0xff));    // low end is blue-ish
  CHECK(((high >> 16) & 0xff) > (high & 0xff));  // high end is red-ish
  CHECK(luma(mid) > luma(low));
  CHECK(luma(mid) > luma(high));
  CHECK(rgb.data[3] == 0u);
  CHECK(rgb.data[4] == 0u);
  // Values outside [lo, hi] clamp to the ends instead of wrapping.
  values.data = {-5.f, 5.f, 0.f, 0.f, 0.f};
  const cs::Image<uint32_t> clamped = cs::colorizeScalar(values, 0.f, 1.f);
  CHECK(clamped.data[0] == low);
  CHECK(clamped.data[1] == high);
  // hi < lo reverses the map.
  CHECK(cs::colorizeScalar(values, 1.f, 0.f).data[0] == high);
}

TEST_CASE("colorizeFlow: white at rest, hue by direction, unknown is black") {
  cs::FlowImage flow(6, 1);
  flow.data = {{0.f, 0.f},
               {2.f, 0.f},
               {-2.f, 0.f},
               {0.f, 2.f},
               {cs::kFloUnknown, 0.f},
               {std::numeric_limits<float>::quiet_NaN(), 0.f}};
  const cs::Image<uint32_t> rgb = cs::colorizeFlow(flow, 2.f);
  CHECK(rgb.data[0] == 0xffffffu);
  CHECK(rgb.data[1] != rgb.data[2]);
  CHECK(rgb.data[1] != rgb.data[3]);
  CHECK(rgb.data[2] != rgb.data[3]);
  for (int i = 1; i < 4; ++i) CHECK(rgb.data[i] != 0xffffffu);
  CHECK(rgb.data[4] == 0u);
  CHECK(rgb.data[5] == 0u);
  CHECK(rgb.data[1] == 0xff0000u);  // rightward flow at full magnitude is pure red
  // Flow beyond maxMagnitude is dimmed, not brighter.
  flow.data[1] = {8.f, 0.f};
  CHECK(luma(cs::colorizeFlow(flow, 2.f).data[1]) < luma(rgb.data[1]));
}

// ------------------------------------------------------------------ shared data

TEST_CASE("shared data: bino01_urban depth and image load") {
  const std::string depthPath = cs::test::sharedData("synthetic/bino01_urban/depth_left.exr");
  const std::string imagePath = cs::test::sharedData("synthetic/bino01_urban/left.png");
  if (depthPath.empty() || imagePath.empty()) {
    MESSAGE("shared data set bino01_urban not present; skipping");
    return;
  }
  const cs::ImageF depth = cs::readExr(depthPath);
  REQUIRE(depth.width == 800);
  REQUIRE(depth.height == 800);
  const float centre = depth(400, 400);
  CHECK(std::isfinite(centre));
  CHECK(centre > 0.f);
  CHECK(depth(0, 0) == 0.f);  // outside the fisheye circle

  const cs::ImageF image = cs::readPngGray(imagePath);
  REQUIRE(image.width == 800);
  REQUIRE(image.height == 800);
  float lo = 1.f, hi = 0.f;
  for (float v : image.data) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  CHECK(lo >= 0.f);
  CHECK(hi <= 1.f);
  CHECK(hi > lo);
}
