// Plain regions filled with the plane their confident border agrees on (Params::plainFill):
// the host's part, between Backend::plainSupport and Backend::fillPlanes
// (docs/confidence.md "Plain surfaces").
#pragma once
#include <Eigen/Core>
#include <vector>

#include "curvestereo/camera.hpp"

namespace cs {

constexpr int kMaxPlainPlanes = 64;
constexpr int kPlainSupportChannels = 6;  // Backend::plainSupport: X, Y, w (2), confidence, window variance
constexpr int kSupportConfidence = 4, kSupportVariance = 5;  // their channels

struct PlainFillParams {
  float noise = 0.01f;                // the level's image noise (grey levels of [0, 1])
  double minShare = 0.005;            // smallest region filled, share of the level's masked pixels
  int supportRadius = 2;              // textured pixels this close (level px) to a region are its border
  double minSupportConfidence = 0.5;  // border pixels less confident than this do not vote
  double inlierPx = 1.0;              // a border pixel agrees with a plane within this (full-resolution px)
  double minInliers = 0.4;            // share of the voting border that must agree
  double minScatter = 0.25;           // the border's residuals (px^2) taken as at least this
  double maxDeviationPx = 1.0;        // a pixel is filled where the plane's deviation is at most this (px)
  double qMax = 0.0;                  // nearest inverse depth accepted (the sweep's nearest sphere)
  double confidenceSigmaPx = 0.5;     // the deviation at which a filled pixel's confidence is 1/2
};

// The planes found at the plain-fill level: each level pixel's plane index (-1: none) and
// the plane's confidence there (2 channels, Backend::fillPlanes' labels), and each plane as
// a, with inverse depth q = a . ray (ray of unit length in camera 0).
struct PlainPlanes {
  std::vector<float> labels;
  std::vector<Eigen::Vector3f> planes;
  int regions = 0;  // plain regions large enough to fill (planes.size() of them agreed on a plane)
  long long pixels = 0;
};

// The unit ray (camera 0, full resolution) through the centre of each pixel of a width x
// height level, the pixels its image moves per unit of inverse depth at infinity, and
// whether the camera model has a ray there: computed once per pose.
struct PlainRays {
  std::vector<Eigen::Vector3f> ray;
  std::vector<float> pxPerQ;
  std::vector<uint8_t> valid;
};
PlainRays plainRays(const Camera& camera0, const Eigen::Vector3d& tPrime, int width, int height);

// At a width x height pyramid level (rays from plainRays): the large plain regions and the
// planes through the inverse depths of their confident textured borders. support is
// Backend::plainSupport's output on the level's grid (full-resolution pixels and warps,
// the level image's variance); camera0 and tPrime are the rig's at full resolution.
PlainPlanes findPlainPlanes(const PlainRays& rays, const Camera& camera0, const Eigen::Vector3d& tPrime, int width,
                            int height, const std::vector<float>& support, const PlainFillParams& p);

}  // namespace cs
