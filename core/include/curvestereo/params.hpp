// Solver parameters, named presets, and the pyramid plan derived from them.
#pragma once
#include <string>
#include <vector>

namespace cs {

struct Params {
  // Pyramid: `levels` levels at scale 1/scale each; fewer if the coarsest width
  // would drop below `minWidth`.
  int levels = 5;
  double scale = 2.0;
  int minWidth = 50;

  // Warping (outer) and primal-dual (inner) iterations per level.
  int warps = 30;
  // Coarse-to-fine travel: the coarsest level starts from nothing and must move the
  // estimate all the way, each finer level only corrects its coarser neighbour's
  // (upsampled) error. Each level warps warpsTaper times fewer than the next coarser one
  // (at least once): `warps` at the coarsest level. 0: every level warps `warps` times.
  int warpsTaper = 0;
  int iterations = 10;
  float duMax = 0.2f;        // clamp of the disparity increment per warp (px of that level)
  bool medianFilter = true;  // 3x3 median of u after each warp's iterations
  // Each level starts from the coarser one's estimate resampled. Bilinear resampling
  // invents disparities between two surfaces at every depth edge, a band a few pixels wide
  // that the few warps after the sweep cannot undo. With edgeUpsample, where the four
  // coarse neighbours of a pixel differ by a pixel or more, the pixel takes the one whose
  // displacement its 5x5 window matches best (Backend::upsampleEstimate). On in the presets
  // with the plane sweep; off here (variational, paper): without the sweep the coarse
  // estimate is least reliable at edges, and the solver alone measured worse with it
  // (docs/accuracy.md "How realtime was chosen").
  bool edgeUpsample = false;

  // Data term (docs/design.md "Per frame", the normalised data term): what the residual rho compares. Normalised: each
  // pyramid level's images after local contrast normalisation (zero mean, unit spread in a
  // Gaussian window of normSigma level px), so a gain and offset per camera and smooth
  // shading (vignetting) cancel and lambda is in units of the local contrast, not of grey
  // levels. Brightness: the grey levels themselves (the paper's term; lambda ~20).
  enum class DataTerm { Brightness, Normalised };
  DataTerm dataTerm = DataTerm::Normalised;
  float normSigma = 4.f;
  // The camera's noise (standard deviation, grey levels of [0, 1]; 0.01 = 2.5 levels of 8
  // bits, about a T265's read plus shot noise at its usual exposure). Contrast below it is
  // not trusted: it floors the normalisation's spread and the sweep's window variances,
  // so noise in flat or dark regions is not stretched into texture. A property of the
  // sensor, not of the scene, hence not tied to the image's contrast.
  float noiseLevel = 0.01f;

  // Energy: lambda |rho| + alpha0 |grad v| + alpha1 |D grad u - v|. lambda's unit is the
  // data term's: kNormalisedLambda for the normalised term, kBrightnessLambda (the paper's)
  // for grey levels; withDataTerm() sets the term and its lambda together.
  static constexpr float kNormalisedLambda = 3.f;
  static constexpr float kBrightnessLambda = 20.f;
  float lambda = kNormalisedLambda;
  float alpha0 = 17.f;
  float alpha1 = 1.2f;
  // Structure tensor D = w n n^T + n_perp n_perp^T, w = max(exp(-beta |grad I|^eta), wMin)
  float beta = 9.f;
  float eta = 0.85f;
  float wMin = 1e-4f;
  float tensorSigma = 1.0f;  // Gaussian smoothing (px) of I0 before its gradient

  // Accelerated primal-dual (Chambolle & Pock 2011, Alg. 2) with strong-convexity
  // estimate gamma; gamma = 0 gives constant steps and theta = 1.
  float gamma = 0.f;

  // Initialisation (docs/design.md "The plane-sweep initialiser"). None: the coarsest level starts at zero
  // disparity, so coarse-to-fine warping reaches about levels x warps x duMax px and
  // larger displacements are lost. PlaneSweep: a plane sweep (spheres uniform in inverse
  // depth, ZNCC aggregated along scanlines, both views) at pyramid level initLevel gives
  // the starting disparity there and a left-right confidence; pixels of low confidence
  // (occlusions, mismatches) weigh at least occlusionWeight in the data term.
  enum class Init { None, PlaneSweep };
  Init init = Init::None;
  // 0 = full resolution; clamped to the coarsest level. Level 1 (half resolution): on
  // images from a real camera the sweep's windows then average four pixels' noise and two
  // levels refine its estimate; with the normalised data term, mean tau>1 over three
  // binocular pairs was 6.0 % at level 1 against 6.7 % at level 0 on T265-like images,
  // and 18.8 % against 28.5 % (non-occluded) on three forward / diagonal ones; on clean
  // renders level 0 keeps a small edge (4.3 / 7.1 % against 4.6 / 8.1 %) since depth
  // edges are placed to a finer pixel. A quarter of the sweep's work. Level 2 is worse
  // on both: the fine levels' linearised data term cannot move edges that far back.
  int initLevel = 1;
  double initMaxParallaxDeg = 40.0;  // nearest hypothesis: a point this many degrees of parallax away
  double initPxPerPlane = 1.0;       // largest image motion between neighbouring hypotheses (level px)
  int initRadius = 2;                // ZNCC window (2r+1)^2 at the sweep level
  // Semi-global aggregation of the window costs (1 - ZNCC, capped at 1) along four
  // scanlines: the penalty of a step to a neighbouring hypothesis, and of any larger jump.
  // The paths let a small window (little fattening at depth edges) vote like a large one.
  // A jump costs as much as one complete mismatch (P2 = the cap): a path changes depth
  // only where the windows disagree with its depth more than that (on the development
  // pairs P2 = 0.25 / 0.5 / 1 gave bino03 tau>1 7.1 / 6.8 / 6.5 % with 8 paths, 6.4 -> 5.9
  // from 0.5 to 1 with these 4 paths and the occlusion fill, sweeping at level 1).
  float initP1 = 0.05f;
  float initP2 = 1.0f;
  float lrTolerancePx = 1.0f;  // left-right round-trip error (level px) where confidence is 1/e
  float initAccept = 0.3679f;  // confidence from which the sweep replaces the coarse estimate (e^-1: e <= tol)
  // A sweep winner whose own window correlates no better than ZNCC 0.05 (cost above 0.95)
  // matched nothing distinct: on a plain surface the noise-floored windows correlate near 0
  // with every hypothesis, and the aggregation carries a neighbour's depth across it the
  // same way in both views, so the left-right check alone would accept it. Such pixels keep
  // the coarse-to-fine estimate. Measured (CPU, realtime, tau>1), 0.95 against no gate: the
  // plain indoor pair 34.09 -> 28.00 %, its T265-like version 39.24 -> 38.25; T265-like
  // textured pairs +0.04 / +0.30 (bino02, temp03). At 0.85 the plain indoor pair fell to
  // 25.14 % but the T265-like textured pairs rose by 0.59 points on average: their noisy
  // windows correlate less, and a tighter gate refuses their true matches. 2: no gate.
  float initMaxCost = 0.95f;
  // Data-term weight floor: pixels weigh max(confidence, occlusionWeight). 1 (no
  // down-weighting) measured best on the development pairs: at the sweep's resolution the
  // check also flags good pixels beside edges, and the regulariser's smooth fill of true
  // occlusions was no better than their own data (bino02 tau>1 5.9 / 6.2 / 6.5 % at 1 /
  // 0.5 / 0.1; temp02 non-occluded 15.8 / 17.3 % at 1 / 0.3).
  float occlusionWeight = 1.0f;
  // Warps per level from the sweep's level down (0 = as the levels above). Once the
  // sweep has placed the surfaces, these levels only refine, and the coarse levels above
  // are what the pixels the check rejects depend on. Measured (CUDA, H100, the 12
  // development pairs, mean tau>1 of clean / T265-like binocular pairs, sweeping at level
  // 1 with 30 warps above): 30 / 10 / 5 / 3 / 2 / 1 warps from the sweep down gave 4.6 /
  // 6.0, 5.8 / 7.0, 5.6 / 6.9, 5.6 / 6.6, 5.5 / 6.4, 5.7 / 6.6 %: a few warps keep nearly
  // all of it; the last point on clean renders (sub-pixel refinement at full resolution)
  // costs ~0.3 ms per 848x800 warp. Skipping the levels above the sweep's instead (the
  // rejected pixels then start at zero) lost 4 to 6 points on the T265-like pairs and is
  // not offered.
  int initWarps = 0;
  // Band sweep (0: off; else 2..32 hypotheses): the full sweep runs one level coarser than
  // initLevel (and initialises that level too), and initLevel scores only initBand
  // hypotheses a pixel around the coarse winner (in the manner of tSGM, Rothermel et al.
  // 2012): a far smaller volume where the coarse level found the surface; where it did
  // not, the winner tends to land on the band's edge and is refused, or the left-right
  // check rejects it, and the pixel keeps the coarse-to-fine estimate. Off (a full sweep)
  // when initLevel is the coarsest level.
  int initBand = 0;

  // Field of view used: rays farther than maxFovDeg/2 from the optical axis are masked
  // (0 = everything the camera model represents, which for an undistorted equidistant
  // model reaches into the black image corners; set it above 180 for wider lenses).
  // Pixels whose ray is closer than epipoleDeg to the baseline direction (where depth is
  // unobservable) are masked too.
  double maxFovDeg = 180.0;
  double epipoleDeg = 3.0;

  // Sequences (Stereo::next; a single pair ignores these). A frame after the first starts
  // from the previous frame's estimate carried into its view (warmStart): it initialises
  // the band sweep's coarse level (which still warps, so the current images correct it),
  // the band sweep searches around it instead of the full coarse sweep, and the levels
  // above are solved briefly (warmCoarseWarps). Needs the plane sweep with a band (realtime); other presets solve
  // every frame cold. Every coldEvery-th frame is solved cold (0: only the first and the
  // failed ones): a warm start can keep an error it never re-examines, such as an object
  // that entered faster than the band follows. A warm frame whose share of left-right
  // consistent pixels, or whose mean result confidence (low where the images disagree with
  // the estimate after the last warp: the data residual), falls below warmFailRatio times
  // that of the last cold frame is solved again, cold. 0 turns the check off, and with it
  // the reads it needs every frame: the sweep level's confidence and a sixteenth-size copy
  // of the result's (Pipeline::meanConfidence).
  bool warmStart = true;
  int coldEvery = 30;
  // Hypotheses a pixel of a warm frame's band sweep (0: initBand's). The carried estimate is
  // the previous frame's solution, so the band needs to span only a frame's change of depth
  // plus its coarse neighbourhood's spread, not a cold coarse sweep's errors: 8 hypotheses
  // reach 4 planes either way, up to 8 px of disparity at full resolution with realtime's
  // spacing (a plane is at most initPxPerPlane px at level 1), where a walking rig's surfaces
  // move well under a pixel a frame. A pixel whose change is larger lands on the
  // band's edge, is refused and keeps the fresh coarse solve. Measured on seqD1 (CUDA = CPU
  // oracle, 16 frames, warm against cold, with 3 coarse warps), band 8 / 16: clean tau>1
  // -2.54 / -2.18 points, flicker x0.36 / x0.40; T265-like -1.68 / -5.68, flicker x0.24 /
  // x0.43, moving box -8.6 / -10.9; band 6 gave the T265-like render only -0.93, so 8 is the
  // narrowest with margin. 0.1 ms less of a 2.5 ms warm frame on an H200.
  int warmBand = 8;
  // Warps at each level above the carried one in a warm frame, solved from zero as in a cold
  // frame (0: those levels are skipped). They give the pixels whose carried estimate fails
  // the left-right check a fresh start from this frame's images; without them such pixels
  // kept the previous frame's coarse solution, and on plain surfaces, where no data corrects
  // it, the error grew by about half a point of tau>1 a frame (seqD1, clean renders, CPU:
  // warm 31.9 % against cold 29.6 % over 16 frames). A short solve suffices there: it needs
  // the coarse shape, not the cold frame's 30 and 20 warps (which cost 1.7 ms on an H200).
  // 3 against 4 (seqD1, band 16): clean -2.18 against -2.91 points, T265-like -5.68 against
  // -6.00; 2 drifts again (CPU: 30.1 % against cold 29.3 % over 11 frames with 2 / 1).
  int warmCoarseWarps = 3;
  // Warps at full resolution in a warm frame (0: initWarps'). The carried estimate arrives
  // there already refined by the band sweep and the level above, and a second warp changed
  // little (seqD1, CPU, 16 frames, 1 against 2: T265-like tau>1 30.81 against 30.67 %,
  // flicker 11.22 against 10.89 %; clean 26.7 both) for 0.2 ms of a 2.8 ms frame on an H200.
  // One warp at the level above too lost more (T265-like 31.42 %, clean moving box +1.2).
  int warmFullResWarps = 1;
  float warmFailRatio = 0.8f;
  // The temporal filter of a sequence's result (Backend::temporalFilter): the previous
  // frame's filtered depth, carried into the new view, is averaged with the new estimate
  // where the two agree within temporalGate standard deviations, the prior weighing at
  // most temporalStrength (0: off; 0.8 averages about the last 9 frames of a static
  // surface); a pixel that disagrees takes the new value at once, so moving objects leave
  // no trail.
  // The gate is 4 standard deviations rather than the textbook 3: the measurement model
  // (half a pixel at full confidence) is a floor, and on a noisy camera more of the
  // solver's real changes exceed it; measured on seqD1 (warm, CUDA, H200), T265-like
  // flicker 11.2 against 12.3 % and moving-object tau>1 16.6 against 19.2 % at a cost of
  // 0.04 points of tau>1 on the clean renders.
  float temporalStrength = 0.8f;
  float temporalGate = 4.f;

  // The result's confidence (DepthResult::confidence; docs/confidence.md), for every preset:
  // the product of the structure along the epipolar curve (how well the image fixes a shift
  // along it), the photometric agreement the final estimate leaves, the sweep's left-right
  // consistency (with the initialiser) and, with lrCheck, the round trip through the other
  // direction's solve. lrCheck solves that other direction too (about twice the time) and
  // leaves invalid (NaN in every output) the pixels whose round trip misses by more than
  // lrCheckPx. A pixel whose disparity is below infinityPx is at infinity (+inf depth): a
  // subpixel estimate resolves about a tenth of a pixel, so a smaller disparity does not
  // tell a far point from one at infinity. So is one whose disparity is within two
  // deviations of the structure term (or of the plane that filled it) of zero and, those
  // added, stays below infinityBoundPx: the image cannot tell it from infinity, and bounds
  // it far (0: only infinityPx). A pixel whose confidence is below rejectBelow
  // is left invalid (0: every solved pixel is kept).
  // A pixel whose image cannot fix its disparity along the curve to within maxDeviationPx
  // (the Cramer-Rao deviation of the structure term) is left invalid rather than given the
  // depth the regulariser carried into it: on plain surfaces and the sky that depth is
  // whatever the nearest texture had, and a sky pixel made a near obstacle is worse than a
  // hole (0: keep them).
  bool lrCheck = false;
  float lrCheckPx = 1.f;
  float infinityPx = 0.1f;
  float infinityBoundPx = 1.f;
  float rejectBelow = 0.f;
  float maxDeviationPx = 0.f;

  // Plain regions (docs/confidence.md "Plain surfaces"): after solving level
  // plainFillLevel, each large connected region whose image varies no more than twice the
  // noise (nothing to match on: painted walls, floors, ceilings) takes the plane that the
  // inverse depths of its textured border agree on, if most of the border agrees and the
  // border fixes the plane across the region to half a pixel; the finer levels then refine
  // it. Without it the regulariser fills such a region from whatever it reaches.
  bool plainFill = true;
  int plainFillLevel = 2;

  // This data term with its default lambda.
  Params withDataTerm(DataTerm term) const;

  // Throws cs::Error naming the first out-of-range value.
  void validate() const;
};

// "brightness" / "normalised"; parseDataTerm throws cs::Error listing the names.
std::string dataTermName(Params::DataTerm term);
Params::DataTerm parseDataTerm(const std::string& name);

// "none" / "planesweep"; parseInit throws cs::Error listing the names.
std::string initName(Params::Init init);
Params::Init parseInit(const std::string& name);

// Named presets: "realtime" (the default of the library, the command line and Python: a
// plane sweep at level 2 and a band of 32 hypotheses a pixel around it at level 1, 30 / 20
// warps at levels 4 / 3, 2 at each level below),
// "fast" (for slower GPUs: the sweep at level 2, then N = 5 warps a level), "quality"
// (the sweep at level 1, then N = 30 at every level), "variational" (the solver alone,
// N = 30, no initialiser: the struct's defaults) and "paper" (the paper's configuration:
// brightness data term, lambda 20, N = 5).
// Throws cs::Error listing the known names for an unknown one.
Params preset(const std::string& name);
std::vector<std::string> presetNames();

struct LevelSize {
  int width, height;
  double scale;  // level width / full width
};

// Level 0 first (full resolution).
std::vector<LevelSize> pyramidPlan(int width, int height, const Params& p);
// An image of width x height at a level of the given scale (as pyramidPlan sizes its levels).
LevelSize levelSize(int width, int height, double scale);

// "levels=5 scale=2 warps=30 ..." for logs and bench reports.
std::string describe(const Params& p);

}  // namespace cs
