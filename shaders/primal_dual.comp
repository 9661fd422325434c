#version 460
#extension GL_GOOGLE_include_directive : require
// Preconditioned primal-dual iterations of anisotropic TGV-L1 (backend_cpu/primal_dual.cpp),
// 1 .. kMaxIterations of them per dispatch: the port of backend_cuda/primal_dual.cu's
// tiled kernel. One invocation per cell of a kCellsW x kCellsH work group, which covers
// its written tile plus a halo of `iterations` cells on every side. Each iteration is a
// dual pass (p, q and D p into shared memory), a barrier, then a primal pass (uBar, vBar
// into shared memory): the dual pass needs its right and lower neighbours' uBar, vBar, the
// primal pass its left and upper neighbours' duals, so each pass runs on one cell less
// than the last, and after `iterations` the tile [iterations, kCells - iterations] is
// exact. The state ping-pongs between two buffer sets (read one, write the other), so a
// work group never reads what another of the same dispatch wrote.
// Every per-pixel expression is the oracle's, in its order (no vector operations, whose
// evaluation order GLSL leaves open).
#define CS_OWN_WORK_GROUP
#include "common.glsl"

// The square tile (-DCS_SQUARE_TILE: 32 x 32 cells, 48 KiB of shared memory, 1024
// invocations) or the wide one (32 x 16, 24 KiB, 512) where the device has them, else
// (-DCS_NARROW_TILE) 16 x 16 cells in 12 KiB, within every device's 16 KiB.
#ifdef CS_NARROW_TILE
const int kCellsW = 16;
#else
const int kCellsW = 32;
#endif
#ifdef CS_SQUARE_TILE
const int kCellsH = 32;  // 32 x 32 cells, 48 KiB: less halo per written pixel
#else
const int kCellsH = 16;
#endif
layout(local_size_x = kCellsW, local_size_y = kCellsH, local_size_z = 1) in;

const int kMaxIterations = 5;  // mirrors kMaxPdIterations in backend_vulkan/kernels.cpp

// The level's solver state and constants. Set 0 is the caller's buffers, set 1 the
// backend's spare set of the same sizes.
layout(buffer_reference, std430, buffer_reference_align = 8) buffer PdLevel {
  FBuf u[2], uBar[2], v[2], vBar[2], p[2], q[2];
  FBuf u0, iu, iz, tensor, steps, mask;
  FBuf uBarFirst, vBarFirst;  // what the call's first dispatch reads as set 0's uBar, vBar
  int w, h;
  float lambda, alpha0, alpha1;
};

// What masked-out pixels (which never change and which no masked pixel reads) need: only
// the call's first dispatch writes them, and only where the call's result needs them.
const int kCopyOutside = 1;  // into the written set (the result ends there)
const int kBarsHome = 2;     // uBarFirst, vBarFirst into set 0's uBar, vBar

layout(push_constant) uniform PC {
  PdLevel level;
  int parity;                 // the set read; 1 - parity is written
  int iterations;             // 1 .. kMaxIterations
  int first;                  // the call's first dispatch: uBar, vBar from uBarFirst, vBarFirst
  int outside;                // kCopyOutside | kBarsHome, on the first dispatch only
  vec4 step[kMaxIterations];  // tauScale, sigmaScale, theta, qAscent = sigma_q alpha0
} pc;

const uint kMasked = 1u, kLinkX = 2u, kLinkY = 4u;

shared vec2 sP[kCellsH][kCellsW];
shared vec2 sDp[kCellsH][kCellsW];  // D p
shared vec4 sQ[kCellsH][kCellsW];
shared float sUBar[kCellsH][kCellsW];
shared vec2 sVBar[kCellsH][kCellsW];
shared uint sFlags[kCellsH][kCellsW];

// What one invocation carries from pass to pass: its cell's state and constants.
struct Cell {
  vec2 p, v, vBar, tau, sigmaP;
  vec4 q, t;
  float u, uBar, u0, iu, iz;
  uint flags;
};

// argmin_u (u - uHat)^2 / (2 tau) + lambda |iz + (u - u0) iu| (cpu operators.hpp dataProx).
float dataProx(float uHat, float u0, float iu, float iz, float tauLambda) {
  const float rho = iz + (uHat - u0) * iu;
  const float threshold = tauLambda * iu * iu;
  if (rho < -threshold) return uHat + tauLambda * iu;
  if (rho > threshold) return uHat - tauLambda * iu;
  if (iu == 0.0) return uHat;
  return uHat - rho / iu;
}

// p <- P(p + sigma_p alpha1 (D grad uBar - vBar)), q <- P(q + sigma_q alpha0 grad vBar)
// (cpu dualUpdate); ur, ud, vr, vd: uBar, vBar to the right and below (used where linked).
void dualPixel(inout Cell c, float ur, float ud, vec2 vr, vec2 vd, vec4 step) {
  const bool ex = (c.flags & kLinkX) != 0u, ey = (c.flags & kLinkY) != 0u;
  const float gx = ex ? ur - c.uBar : 0.0, gy = ey ? ud - c.uBar : 0.0;
  const float a1 = c.t.x * gx + c.t.y * gy - c.vBar.x;
  const float a2 = c.t.y * gx + c.t.z * gy - c.vBar.y;
  float p0 = c.p.x + step.y * c.sigmaP.x * pc.level.alpha1 * a1;
  float p1 = c.p.y + step.y * c.sigmaP.y * pc.level.alpha1 * a2;
  const float norm = sqrt(p0 * p0 + p1 * p1);
  if (norm > 1.0) {
    p0 /= norm;
    p1 /= norm;
  }
  c.p = vec2(p0, p1);
  // grad v: (d/dx v0, d/dy v0, d/dx v1, d/dy v1).
  const float g[4] = float[4](ex ? vr.x - c.vBar.x : 0.0, ey ? vd.x - c.vBar.x : 0.0, ex ? vr.y - c.vBar.y : 0.0,
                              ey ? vd.y - c.vBar.y : 0.0);
  float q[4];
  float s = 0.0;
  for (int k = 0; k < 4; ++k) {
    q[k] = c.q[k] + step.w * g[k];
    s += q[k] * q[k];
  }
  const float qn = sqrt(s);
  for (int k = 0; k < 4; ++k) c.q[k] = qn > 1.0 ? q[k] / qn : q[k];
}

// The cell's duals into shared memory, for its neighbours' primal pass.
void shareDuals(ivec2 l, Cell c) {
  sP[l.y][l.x] = c.p;
  sQ[l.y][l.x] = c.q;
  sDp[l.y][l.x] = vec2(c.t.x * c.p.x + c.t.y * c.p.y, c.t.y * c.p.x + c.t.z * c.p.y);
}

// div of a field given as its x and y components here and at the left / upper neighbour
// (cpu operators.hpp divergence: zero across image and mask borders).
float divergence(bool ex, bool exLeft, bool ey, bool eyUp, float x, float xLeft, float y, float yUp) {
  float d = 0.0;
  if (ex) d += x;
  if (exLeft) d -= xLeft;
  if (ey) d += y;
  if (eyUp) d -= yUp;
  return d;
}

// u <- prox(u + tau_u alpha1 div(D p)), v <- v + tau_v (alpha1 p + alpha0 div q) and the
// over-relaxed uBar, vBar (cpu primalUpdate), from the duals in shared memory.
void primalPixel(ivec2 l, inout Cell c, vec4 step) {
  const bool ex = (c.flags & kLinkX) != 0u, ey = (c.flags & kLinkY) != 0u;
  const bool exLeft = (sFlags[l.y][l.x - 1] & kLinkX) != 0u, eyUp = (sFlags[l.y - 1][l.x] & kLinkY) != 0u;
  const float tauU = step.x * c.tau.x, tauV = step.x * c.tau.y;
  const float divDp =
      divergence(ex, exLeft, ey, eyUp, sDp[l.y][l.x].x, sDp[l.y][l.x - 1].x, sDp[l.y][l.x].y, sDp[l.y - 1][l.x].y);
  const float uOld = c.u;
  const float uHat = uOld + tauU * pc.level.alpha1 * divDp;
  c.u = dataProx(uHat, c.u0, c.iu, c.iz, tauU * pc.level.lambda);
  c.uBar = c.u + step.z * (c.u - uOld);
  const vec4 q = sQ[l.y][l.x], qLeft = sQ[l.y][l.x - 1], qUp = sQ[l.y - 1][l.x];
  const float div0 = divergence(ex, exLeft, ey, eyUp, q.x, qLeft.x, q.y, qUp.y);
  const float div1 = divergence(ex, exLeft, ey, eyUp, q.z, qLeft.z, q.w, qUp.w);
  const vec2 p = sP[l.y][l.x], vOld = c.v;
  const float v0 = vOld.x + tauV * (pc.level.alpha1 * p.x + pc.level.alpha0 * div0);
  const float v1 = vOld.y + tauV * (pc.level.alpha1 * p.y + pc.level.alpha0 * div1);
  c.v = vec2(v0, v1);
  c.vBar = vec2(v0 + step.z * (v0 - vOld.x), v1 + step.z * (v1 - vOld.y));
}

// The 2- and 4-channel buffers' pixels as one vector access each (buffers start 16-byte
// aligned: memory.cpp).
layout(buffer_reference, std430, buffer_reference_align = 8) buffer V2Buf { vec2 v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer V4Buf { vec4 v[]; };
vec2 load2(FBuf b, int i) { return V2Buf(b).v[i]; }
vec4 load4(FBuf b, int i) { return V4Buf(b).v[i]; }
void store2(FBuf b, int i, vec2 x) { V2Buf(b).v[i] = x; }
void store4(FBuf b, int i, vec4 x) { V4Buf(b).v[i] = x; }

bool maskedAt(int i, int j) {
  return i >= 0 && j >= 0 && i < pc.level.w && j < pc.level.h && pc.level.mask.v[j * pc.level.w + i] != 0.0;
}

// Loads the state and constants of the in-image cell (i, j) and runs the first
// iteration's dual pass on it with its neighbours' uBar, vBar from memory.
Cell loadAndDual(int i, int j) {
  PdLevel s = pc.level;
  const int idx = j * s.w + i, r = pc.parity;
  FBuf uBarIn = pc.first != 0 ? s.uBarFirst : s.uBar[r], vBarIn = pc.first != 0 ? s.vBarFirst : s.vBar[r];
  Cell c;
  c.p = load2(s.p[r], idx);
  c.q = load4(s.q[r], idx);
  c.u = s.u[r].v[idx];
  c.v = load2(s.v[r], idx);
  c.uBar = uBarIn.v[idx];
  c.vBar = load2(vBarIn, idx);
  const vec4 st = load4(s.steps, idx);
  c.tau = st.xy;
  c.sigmaP = st.zw;
  c.t = vec4(0.0);
  c.flags = 0u;
  if (s.mask.v[idx] == 0.0) return c;
  c.flags = kMasked | (maskedAt(i + 1, j) ? kLinkX : 0u) | (maskedAt(i, j + 1) ? kLinkY : 0u);
  c.t = load4(s.tensor, idx);
  c.u0 = s.u0.v[idx];
  c.iu = s.iu.v[idx];
  c.iz = s.iz.v[idx];
  const bool ex = (c.flags & kLinkX) != 0u, ey = (c.flags & kLinkY) != 0u;
  const float ur = ex ? uBarIn.v[idx + 1] : 0.0, ud = ey ? uBarIn.v[idx + s.w] : 0.0;
  const vec2 vr = ex ? load2(vBarIn, idx + 1) : vec2(0.0), vd = ey ? load2(vBarIn, idx + s.w) : vec2(0.0);
  dualPixel(c, ur, ud, vr, vd, pc.step[0]);
  return c;
}

// A later iteration's dual pass, its neighbours' uBar, vBar from shared memory.
void dualFromShared(ivec2 l, inout Cell c, vec4 step) {
  const bool ex = (c.flags & kLinkX) != 0u, ey = (c.flags & kLinkY) != 0u;
  const float ur = ex ? sUBar[l.y][l.x + 1] : 0.0, ud = ey ? sUBar[l.y + 1][l.x] : 0.0;
  const vec2 vr = ex ? sVBar[l.y][l.x + 1] : vec2(0.0), vd = ey ? sVBar[l.y + 1][l.x] : vec2(0.0);
  dualPixel(c, ur, ud, vr, vd, step);
}

void storeState(FBuf u, FBuf uBar, FBuf v, FBuf vBar, int idx, Cell c) {
  u.v[idx] = c.u;
  uBar.v[idx] = c.uBar;
  store2(v, idx, c.v);
  store2(vBar, idx, c.vBar);
}

void main() {
  const int iterations = pc.iterations;
  const ivec2 l = ivec2(gl_LocalInvocationID.xy);
  const ivec2 tile = ivec2(kCellsW, kCellsH) + 1 - 2 * iterations;
  const ivec2 g = ivec2(gl_WorkGroupID.xy) * tile - iterations + l;
  PdLevel s = pc.level;
  const bool inImage = g.x >= 0 && g.y >= 0 && g.x < s.w && g.y < s.h;
  const int idx = g.y * s.w + g.x;
  const bool live = inImage && (pc.outside != 0 || s.mask.v[idx] != 0.0);
  Cell c;
  c.p = c.v = c.vBar = vec2(0.0);
  c.q = c.t = vec4(0.0);
  c.u = c.uBar = 0.0;
  c.flags = 0u;
  if (live) c = loadAndDual(g.x, g.y);
  const bool masked = (c.flags & kMasked) != 0u;
  // The written tile; its masked-out pixels only where the result needs them.
  const bool own = live && all(greaterThanEqual(l, ivec2(iterations))) &&
                   all(lessThanEqual(l, ivec2(kCellsW, kCellsH) - iterations));
  const bool writes = own && (masked || (pc.outside & kCopyOutside) != 0);
  sFlags[l.y][l.x] = c.flags;
  shareDuals(l, c);
  for (int it = 0; it < iterations; ++it) {
    // The dual pass on [it, kCells - 1 - it] (iteration 0's ran at the load; only masked
    // cells change).
    const bool dualCell = all(greaterThanEqual(l, ivec2(it))) && all(lessThan(l, ivec2(kCellsW, kCellsH) - it));
    if (it > 0 && dualCell && masked) {
      dualFromShared(l, c, pc.step[it]);
      shareDuals(l, c);
    }
    barrier();
    // The primal pass on [it + 1, kCells - 1 - it]; its uBar, vBar for the next dual pass.
    if (dualCell && all(greaterThan(l, ivec2(it))) && masked) primalPixel(l, c, pc.step[it]);
    if (it + 1 < iterations) {
      sUBar[l.y][l.x] = c.uBar;
      sVBar[l.y][l.x] = c.vBar;
      barrier();
    }
  }
  if (writes) {
    const int w = 1 - pc.parity;
    store2(s.p[w], idx, c.p);
    store4(s.q[w], idx, c.q);
    storeState(s.u[w], s.uBar[w], s.v[w], s.vBar[w], idx, c);
  }
  if (own && !masked && (pc.outside & kBarsHome) != 0) {
    s.uBar[0].v[idx] = c.uBar;
    store2(s.vBar[0], idx, c.vBar);
  }
}
