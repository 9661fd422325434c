// File formats without OpenCV: PNG, OpenEXR, Middlebury .flo, PLY, and colour maps.
// Every reader throws cs::Error with a one-line message naming the file on failure.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "curvestereo/image.hpp"

namespace cs {

// What a PNG file held before readPngGray converted it (for callers that report it).
struct PngFormat {
  int bitDepth = 0;     // 1, 2, 4, 8 or 16 (per sample, as stored)
  bool colour = false;  // RGB, RGBA or palette: converted to luma
  bool alpha = false;   // an alpha channel or tRNS transparency: dropped
};

// 8- or 16-bit PNG, gray / gray+alpha / RGB / RGBA / palette; colour is converted to
// luma (Rec. 601 weights), alpha dropped. Values scaled to [0, 1]. `format` (optional)
// receives what the file held. With `bytes`, a camera's 8-bit gray file (one channel, not
// interlaced) is returned there as stored, and the float image returned is empty
// (Stereo takes either; unitFromByte converts).
ImageF readPngGray(const std::string& path, PngFormat* format = nullptr, ImageU8* bytes = nullptr);
// The same from a PNG held in memory (a log's CompressedImage); `name` names it in errors.
ImageF decodePngGray(const uint8_t* data, size_t size, const std::string& name, PngFormat* format = nullptr);
void writePngGray(const std::string& path, const ImageF& img);          // clamps to [0,1], 8-bit
void writePngGray16(const std::string& path, const ImageF& img);        // clamps to [0,1], 16-bit
void writePngRgb(const std::string& path, const Image<uint32_t>& rgb);  // 0x00RRGGBB per pixel

// Single-channel float EXR. The reader takes channel "Y" if present, else "R", else the
// first channel; the writer writes channel "Y", 32-bit float, ZIP compression.
ImageF readExr(const std::string& path);
void writeExr(const std::string& path, const ImageF& img);

// Middlebury .flo ("PIEH", width, height, interleaved u v float32).
// Components with |value| >= 1e9 mean unknown; the writer writes 1e10 for unknown.
constexpr float kFloUnknown = 1e10f;
FlowImage readFlo(const std::string& path);
void writeFlo(const std::string& path, const FlowImage& flow);

// Binary little-endian PLY with x y z (float) and optional gray (uchar) per vertex.
struct PlyPoint {
  float x, y, z;
  uint8_t gray;
};
void writePly(const std::string& path, const std::vector<PlyPoint>& points);

// Colour maps for people to look at. Values outside the valid mask (or non-finite)
// become black.
Image<uint32_t> colorizeScalar(const ImageF& values, float lo, float hi);  // turbo-like map
Image<uint32_t> colorizeFlow(const FlowImage& flow, float maxMagnitude);   // Middlebury colour wheel
// Radial depth as people look at it (run's depth.png): inverse depth on colorizeScalar's
// map, its range the 2nd / 98th percentile so that a few outliers do not wash it out;
// invalid (NaN, <= 0) black, infinity (zero disparity) at inverse depth 0.
Image<uint32_t> depthPicture(const ImageF& radialDepth);

}  // namespace cs
