#version 460
#extension GL_GOOGLE_include_directive : require
// Local contrast normalisation in one dispatch (backend_cuda/normalise.cu's tiled kernel):
// a work group takes a 32 x CS_TILE_H tile of outputs, with its src and mask and a halo of
// r pixels on every side in shared memory; then the row sums of normalise_moments.comp for
// the tile's columns over its rows and the r rows above and below, in shared memory; then
// normalise.comp's column sums and output. No launch between the passes and no round trip
// of the row sums through global memory (12 bytes a pixel each way). Every sum is taken in
// the two passes' order with the same `precise` expressions: their bits. For radii up to
// kMaxTiledRadius (the host takes the two passes beyond); CS_TILE_H 32 or 16 (the device's
// shared memory decides).
#define CS_OWN_WORK_GROUP
#include "normalise.glsl"

const int kTileW = 32, kBlockH = 16, kMaxTiledRadius = 12;
const int kTileH = CS_TILE_H;
const int kRows = kTileH + 2 * kMaxTiledRadius, kCols = kTileW + 2 * kMaxTiledRadius;
layout(local_size_x = kTileW, local_size_y = kBlockH, local_size_z = 1) in;

layout(push_constant) uniform PC {
  FBuf dst, src, mask;
  NormaliseParamsRef prm;
  int w, h;
} pc;

shared float sSrc[kRows][kCols];
shared uint sMask[kRows][(kCols + 31) / 32];  // bit hx % 32 of word hx / 32: masked()
shared float sS0[kRows][kTileW], sS1[kRows][kTileW], sS2[kRows][kTileW];

bool inTile(int hy, int hx) { return (sMask[hy][hx >> 5] & (1u << (hx & 31))) != 0u; }

// src and mask of the tile and halo, whose [0][0] is pixel (x0, y0); src only where masked
// (the passes read no other value).
void loadTile(int x0, int y0, int rows, int cols) {
  const int tx = int(gl_LocalInvocationID.x), ty = int(gl_LocalInvocationID.y);
  for (int hy = ty; hy < rows; hy += kBlockH)
    for (int k = tx; k < (cols + 31) / 32; k += kTileW) sMask[hy][k] = 0u;
  barrier();
  for (int hy = ty; hy < rows; hy += kBlockH)
    for (int hx = tx; hx < cols; hx += kTileW) {
      const int x = x0 + hx, y = y0 + hy;
      const bool inside = masked(pc.mask, pc.w, pc.h, x, y);
      sSrc[hy][hx] = inside ? pc.src.v[y * pc.w + x] : 0.0;
      if (inside) atomicOr(sMask[hy][hx >> 5], 1u << (hx & 31));
    }
}

// normalise_moments.comp's sums for column x of the tile over the tile's and halo's rows
// inside the image (the column pass skips the others); halo row hy is image row y0 + hy.
void rowSums(int x, int y0, int r, int rows) {
  const int tx = int(gl_LocalInvocationID.x), ty = int(gl_LocalInvocationID.y);
  if (x >= pc.w) return;
  for (int hy = ty; hy < rows; hy += kBlockH) {
    if (y0 + hy < 0 || y0 + hy >= pc.h) continue;
    precise float s0 = 0.0, s1 = 0.0, s2 = 0.0;
    for (int i = -r; i <= r; ++i) {  // the tap at offset i is at halo column tx + r + i
      if (!inTile(hy, tx + r + i)) continue;
      float t = pc.prm.taps[i + r], v = sSrc[hy][tx + r + i];
      s0 += t;
      s1 += t * v;
      s2 += t * (v * v);
    }
    sS0[hy][tx] = s0;
    sS1[hy][tx] = s1;
    sS2[hy][tx] = s2;
  }
}

// normalise.comp for the tile's outputs in column x, from the row sums; the tile's row ty
// is image row y0 + ty, halo row ty + r.
void normaliseColumn(int x, int y0, int r) {
  const int tx = int(gl_LocalInvocationID.x);
  if (x >= pc.w) return;
  for (int ty = int(gl_LocalInvocationID.y); ty < kTileH && y0 + ty < pc.h; ty += kBlockH) {
    const int y = y0 + ty;
    if (!inTile(ty + r, tx + r)) {
      pc.dst.v[y * pc.w + x] = 0.0;
      continue;
    }
    precise float s0 = 0.0, s1 = 0.0, s2 = 0.0;
    for (int j = -r; j <= r; ++j) {
      if (y + j < 0 || y + j >= pc.h) continue;
      float t = pc.prm.taps[j + r];
      s0 += t * sS0[ty + r + j][tx];
      s1 += t * sS1[ty + r + j][tx];
      s2 += t * sS2[ty + r + j][tx];
    }
    float eps = pc.prm.epsilon;
    precise float mean = s1 / s0;
    precise float variance = max(0.0, s2 / s0 - mean * mean);
    precise float value = (sSrc[ty + r][tx + r] - mean) / sqrt(variance + eps * eps);
    pc.dst.v[y * pc.w + x] = value;
  }
}

void main() {
  const int r = pc.prm.radius;  // <= kMaxTiledRadius (the host checks)
  const int x0 = int(gl_WorkGroupID.x) * kTileW, y0 = int(gl_WorkGroupID.y) * kTileH;
  const int x = x0 + int(gl_LocalInvocationID.x);
  loadTile(x0 - r, y0 - r, kTileH + 2 * r, kTileW + 2 * r);
  barrier();
  rowSums(x, y0 - r, r, kTileH + 2 * r);
  barrier();
  normaliseColumn(x, y0, r);
}
