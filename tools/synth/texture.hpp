// Procedural, view-independent surface texture for the synthetic renderer.
//
// Every surface carries a solid (3-D) texture evaluated at the world point, so no
// surface needs a parametrisation and faces of one object join without seams. The
// texture is band-limited by a per-point "footprint" (metres) that the scene derives
// from the point's distance to a fixed anchor (camera 0), never from the viewing ray:
// the brightness of a point is therefore the same in every view (matte), while detail
// that would be far below a pixel is faded out instead of aliasing.
#pragma once
#include <Eigen/Core>
#include <cstdint>

namespace cs::synth {

class Random;

enum class Pattern { Blobs, Cells, Checker, Stripes };

struct Material {
  uint32_t seed = 1;
  Pattern pattern = Pattern::Blobs;
  double noiseScale = 1.0;                              // wavelength of the coarsest noise octave (m)
  double patternScale = 0.3;                            // blob / cell / checker / stripe size at the finest level (m)
  double bias = 0.0;                                    // shifts the mean albedo (tanh domain)
  double contrast = 1.2;                                // gain of the texture signal (tanh domain)
  Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();  // rotates the texture lattice
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
};

// A random material whose pattern features are about `patternScale` metres.
Material randomMaterial(Random& random, double patternScale);

// Albedo in (0, 1) at world point p, band-limited for a footprint (m) of one pixel.
double textureAlbedo(const Material& material, const Eigen::Vector3d& p, double footprint);

// Brightness of the sky in world direction dir (unit, z up): ~0.95, smooth.
double skyBrightness(const Eigen::Vector3d& dir);

}  // namespace cs::synth
