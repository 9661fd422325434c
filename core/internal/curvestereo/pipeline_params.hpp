// What the pipeline derives from Params besides the pyramid's sizes (pyramidPlan, public in
// params.hpp): the normalisation kernel's parameters, the sweep's level and the warps of each
// level. Internal, as backend.hpp: the pipeline and the tests use it; user code has no need.
#pragma once
#include <vector>

#include "curvestereo/kernel_params.hpp"
#include "curvestereo/params.hpp"

namespace cs {

// The normalisation kernel's taps for p.normSigma and its floor p.noiseLevel.
NormaliseParams normaliseParams(const Params& p);

// The level the plane sweep runs at among `levels` pyramid levels: initLevel, clamped to
// the coarsest.
int sweepLevel(const Params& p, int levels);

// Whether the sweep is a band sweep among `levels` pyramid levels: initBand set and a level
// coarser than sweepLevel to run the full sweep at.
bool sweepBanded(const Params& p, int levels);

// Warps at each of `levels` pyramid levels (level 0 first): warps at the coarsest, warpsTaper
// fewer at each finer one (at least 1), initWarps from the first level a sweep initialises
// down when set (sweepLevel, or the one above it with a band: its full sweep initialises it).
// warm: a sequence's warm frame (band sweep only): warmCoarseWarps at the levels above the
// carried one (0: those levels are skipped) and warmFullResWarps (when > 0) at level 0.
std::vector<int> warpSchedule(const Params& p, int levels, bool warm = false);

}  // namespace cs
