#include "synth/texture.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "synth/random.hpp"

namespace cs::synth {
namespace {

using Eigen::Vector3d;

// Integer lattice hash: each coordinate is multiplied by its own odd constant so that
// neighbouring cells differ in many bits, then a 32-bit avalanche mixes them.
uint32_t hashCell(int32_t x, int32_t y, int32_t z, uint32_t seed) {
  uint32_t h = seed * 0x9E3779B1u;
  h ^= uint32_t(x) * 0x85EBCA77u;
  h ^= uint32_t(y) * 0xC2B2AE3Du;
  h ^= uint32_t(z) * 0x27D4EB2Fu;
  h ^= h >> 16;
  h *= 0x7FEB352Du;
  h ^= h >> 15;
  h *= 0x846CA68Bu;
  h ^= h >> 16;
  return h;
}

// Hash to [-1, 1].
double signedUnit(uint32_t h) { return double(h) * (2.0 / 4294967295.0) - 1.0; }

// Quintic fade: C2-continuous, so the noise has no visible lattice creases.
double fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

double smoothstep(double edge0, double edge1, double x) {
  const double t = std::clamp((x - edge0) / (edge1 - edge0), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

double lerp(double a, double b, double t) { return a + (b - a) * t; }

// A pseudo-random gradient per lattice corner: one of the 12 directions towards the
// edge midpoints of a cube (Perlin's choice: no axis is preferred).
double cornerDot(uint32_t h, double x, double y, double z) {
  switch (h % 12u) {
    case 0:
      return x + y;
    case 1:
      return -x + y;
    case 2:
      return x - y;
    case 3:
      return -x - y;
    case 4:
      return x + z;
    case 5:
      return -x + z;
    case 6:
      return x - z;
    case 7:
      return -x - z;
    case 8:
      return y + z;
    case 9:
      return -y + z;
    case 10:
      return y - z;
    default:
      return -y - z;
  }
}

// 3-D gradient noise, roughly in [-1, 1], unit lattice spacing. Unlike value noise its
// blobs show no lattice-aligned squares, which matters once it is thresholded.
double gradientNoise(const Vector3d& q, uint32_t seed) {
  const double fx = std::floor(q.x()), fy = std::floor(q.y()), fz = std::floor(q.z());
  const int32_t ix = int32_t(fx), iy = int32_t(fy), iz = int32_t(fz);
  const double rx = q.x() - fx, ry = q.y() - fy, rz = q.z() - fz;
  auto corner = [&](int dx, int dy, int dz) {
    return cornerDot(hashCell(ix + dx, iy + dy, iz + dz, seed), rx - dx, ry - dy, rz - dz);
  };
  const double tx = fade(rx), ty = fade(ry), tz = fade(rz);
  const double x00 = lerp(corner(0, 0, 0), corner(1, 0, 0), tx);
  const double x10 = lerp(corner(0, 1, 0), corner(1, 1, 0), tx);
  const double x01 = lerp(corner(0, 0, 1), corner(1, 0, 1), tx);
  const double x11 = lerp(corner(0, 1, 1), corner(1, 1, 1), tx);
  return lerp(lerp(x00, x10, ty), lerp(x01, x11, ty), tz);
}

// Visibility of a feature of size `wavelength` for a pixel footprint: 0 below ~2.5
// pixels (it would alias), 1 from 5 pixels on, smooth in between.
double bandWeight(double wavelength, double footprint, double lowPixels, double highPixels) {
  return smoothstep(lowPixels, highPixels, wavelength / footprint);
}

// Multi-octave value noise (fractal sum), octaves below the footprint faded out.
double fractalNoise(const Vector3d& q, double coarsestWavelength, double footprint, uint32_t seed) {
  constexpr double kGain = 0.85;  // slow decay keeps fine octaves contrasty (stereo needs them)
  double sum = 0.0, amplitude = 1.0, wavelength = coarsestWavelength;
  for (int octave = 0; octave < 14; ++octave) {
    const double weight = bandWeight(wavelength, footprint, 2.5, 5.0);
    if (weight <= 0.0) break;
    // The shift keeps the octaves' lattices (where gradient noise is zero) apart.
    const Vector3d shift = double(octave) * Vector3d(0.37, 0.61, 0.13);
    sum += amplitude * weight * gradientNoise(q / wavelength + shift, seed + uint32_t(octave) * 101u);
    amplitude *= kGain;
    wavelength *= 0.5;
  }
  return sum;
}

// Voronoi cells (unit feature spacing): a per-cell grey level minus a dark seam where
// two cells meet, like stone pavement / cracked plaster.
double cells(const Vector3d& q, uint32_t seed) {
  const int32_t cx = int32_t(std::floor(q.x())), cy = int32_t(std::floor(q.y())), cz = int32_t(std::floor(q.z()));
  double nearest = 1e9, second = 1e9;
  uint32_t nearestId = 0;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const uint32_t h = hashCell(cx + dx, cy + dy, cz + dz, seed);
        // Three 10-bit jitters from one hash place the cell's feature point.
        const Vector3d feature(cx + dx + double(h & 1023u) / 1023.0, cy + dy + double((h >> 10) & 1023u) / 1023.0,
                               cz + dz + double((h >> 20) & 1023u) / 1023.0);
        const double d2 = (feature - q).squaredNorm();
        if (d2 < nearest) {
          second = nearest;
          nearest = d2;
          nearestId = h;
        } else if (d2 < second) {
          second = d2;
        }
      }
  const double seamDistance = std::sqrt(second) - std::sqrt(nearest);
  const double seam = 1.0 - smoothstep(0.04, 0.12, seamDistance);
  return 0.9 * signedUnit(hashCell(int32_t(nearestId), 7, 11, seed)) - 1.4 * seam;
}

// 3-D checkerboard: cut by a tilted surface it becomes diamonds and triangles.
double checker(const Vector3d& q) {
  const long parity = long(std::floor(q.x())) + long(std::floor(q.y())) + long(std::floor(q.z()));
  return (parity & 1) ? 0.8 : -0.8;
}

// Bands warped by low-frequency noise (marble / wood grain).
double stripes(const Vector3d& q, uint32_t seed) {
  const double warp = 1.5 * gradientNoise(q * 0.5, seed) + 0.5 * gradientNoise(q * 1.3, seed + 1u);
  return std::sin(2.0 * M_PI * (q.x() + warp));
}

// Soft-edged blobs: thresholded noise.
double blobs(const Vector3d& q, uint32_t seed) { return 1.6 * smoothstep(-0.15, 0.15, gradientNoise(q, seed)) - 0.8; }

// One pattern evaluation at unit feature size.
double patternAt(Pattern pattern, const Vector3d& q, uint32_t seed) {
  switch (pattern) {
    case Pattern::Cells:
      return cells(q, seed);
    case Pattern::Checker:
      return checker(q);
    case Pattern::Stripes:
      return stripes(q, seed);
    case Pattern::Blobs:
      break;
  }
  return blobs(q, seed);
}

// The pattern at the finest scale the footprint allows: scales grow by 4 and cross-fade,
// so e.g. a ground plane shows small cells nearby and large ones far away.
double multiScalePattern(const Material& m, const Vector3d& q, double footprint) {
  const double lowPixels = m.pattern == Pattern::Cells ? 6.0 : 4.0;  // seams need room
  double remaining = 1.0, sum = 0.0, scale = m.patternScale;
  for (int level = 0; level < 6 && remaining > 1e-3; ++level) {
    const double weight = remaining * bandWeight(scale, footprint, lowPixels, 2.0 * lowPixels);
    if (weight > 0.0) sum += weight * patternAt(m.pattern, q / scale, m.seed + 7919u * uint32_t(level + 1));
    remaining -= weight;
    scale *= 4.0;
  }
  return sum;
}

Eigen::Matrix3d randomRotation(Random& random) {
  const double yaw = random.uniform(0, 2 * M_PI), pitch = random.uniform(0, 2 * M_PI),
               roll = random.uniform(0, 2 * M_PI);
  return (Eigen::AngleAxisd(yaw, Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Vector3d::UnitX()))
      .toRotationMatrix();
}

}  // namespace

Material randomMaterial(Random& random, double patternScale) {
  Material m;
  m.seed = random.bits();
  m.pattern = Pattern(random.integer(0, 3));
  m.patternScale = patternScale * random.uniform(0.7, 1.4);
  m.noiseScale = patternScale * random.uniform(2.0, 6.0);
  m.bias = random.uniform(-0.35, 0.35);
  m.contrast = random.uniform(0.9, 1.4);
  m.frame = randomRotation(random);
  m.offset = Vector3d{random.uniform(-100, 100), random.uniform(-100, 100), random.uniform(-100, 100)};
  return m;
}

double textureAlbedo(const Material& m, const Vector3d& p, double footprint) {
  const Vector3d q = m.frame * (p + m.offset);
  const double noise = fractalNoise(q, m.noiseScale, footprint, m.seed);
  const double pattern = multiScalePattern(m, q, footprint);
  // tanh instead of clamping: no flat saturated patches, which would be untextured.
  return 0.5 + 0.5 * std::tanh(m.bias + m.contrast * (noise + 0.5 * pattern));
}

double skyBrightness(const Vector3d& dir) {
  const double elevation = std::asin(std::clamp(dir.z(), -1.0, 1.0));
  const double gradient = 0.08 * std::max(elevation, 0.0) / (0.5 * M_PI);
  // Faint, very low-frequency clouds: the sky is nearly untextured, as in real images.
  const double clouds = 0.04 * gradientNoise(dir * 2.5, 4242u) + 0.02 * gradientNoise(dir * 5.0, 4243u);
  return 0.955 - gradient + clouds;
}

}  // namespace cs::synth
