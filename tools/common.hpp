// Pieces the sub-commands share: parameters from options, inputs, outputs, progress.
#pragma once
#include <set>
#include <string>
#include <vector>

#include "args.hpp"
#include "curvestereo/params.hpp"
#include "curvestereo/rig.hpp"
#include "curvestereo/stereo.hpp"

namespace cs::cli {

// Options every solving command accepts (for allowOnly()).
extern const std::set<std::string> kSolverOptions;

// --preset NAME plus an option per parameter of cs::paramTable() (--warps, --du-max,
// --median on|off, --data-term normalised|brightness, ...; an alias's spelling or the
// full name: --max-fov or --max-fov-deg), validated.
Params paramsFromArgs(const Args& args);

// The usage text's lines for those options, from the same table.
std::string solverUsage();

// The backend spec for Stereo: --backend NAME plus --device INDEX|NAME-SUBSTRING
// ("vulkan" + "1" -> "vulkan:1").
std::string backendFromArgs(const Args& args);

// A gray image (8/16-bit; colour is converted to luma, with a note on stderr).
ImageF loadImage(const std::string& path, const char* which);
// The same, checked against the rig's resolution (one-line error otherwise).
ImageF loadImageFor(const std::string& path, const Camera& cam, const char* which);

// A calibration and a stereo pair checked against each other: same size left and right,
// and the calibration's resolution. With scaleIntrinsics, images that are a uniform
// rescale of the calibrated resolution (e.g. a half-resolution T265 pair) get the
// cameras scaled to them (Camera::scaled, a note on stderr); otherwise a one-line error.
struct StereoInputs {
  Rig rig;
  ImageF left, right;
};
// --image-size WxH: the image size for calibration files that store none.
CalibHints calibHintsFromArgs(const Args& args);
StereoInputs loadStereoInputs(const std::string& calib, const std::string& leftPath, const std::string& rightPath,
                              bool scaleIntrinsics);

// Writes depth.exr, depth.png, disparity.exr, flow.flo, points.ply and confidence.exr /
// confidence.png (when selected) into dir; the left image colours the point cloud, which
// keeps only points of confidence >= minConfidence.
void writeOutputs(const std::string& dir, const DepthResult& result, const ImageF& left, float minConfidence = 0.f);

// points.pcd in dir: the organised cloud, which keeps its grid (points below minConfidence
// become NaN).
void writeOrganisedCloud(const std::string& dir, const DepthResult& result, float minConfidence);

// --min-confidence (0 when absent); an error outside [0, 1].
float minConfidenceFromArgs(const Args& args);

// A colour picture of radial depth: inverse depth on a perceptual map, invalid black.
void writeDepthPng(const std::string& path, const ImageF& radialDepth);

// A one-line progress display on stderr ("label  42%"), quiet when stderr is not a
// terminal unless forced.
class Progress {
 public:
  explicit Progress(std::string label);
  void operator()(double fraction);
  void done();

 private:
  std::string label_;
  int lastPercent_ = -1;
  bool tty_;
};

// "upload 0.4 | pyramid 3.1 | ..." for the stage times of one frame.
std::string formatStages(const std::vector<StageTime>& stages);

// A lens mask PNG (non-zero = use the pixel), e.g. the T265's image circle.
ImageU8 loadMask(const std::string& path);

// A sequence's calibration: --calib, or the sequence folder's own camchain.yaml (the ASL
// layout keeps it there; a note says so); else a one-line error.
std::string sequenceCalibration(const Args& args, const std::string& source);

// --read-threads N: the threads reading frames ahead of the solve (SequenceReader; 0 or
// absent: chosen by the core count). Throws UsageError on anything but 0 to 64.
int readThreads(const Args& args);
// The median, min and max of a benchmark's timings (at least one).
struct Summary {
  double median, min, max;
};
Summary summarize(std::vector<double> v);

// A whole number that is all of text.
bool wholeNumber(const std::string& text, int& out);
// --frames FIRST:END of a sequence of n frames: [FIRST, END) (either may be left out);
// all of them without the option.
std::pair<size_t, size_t> frameRange(const Args& args, size_t n);

}  // namespace cs::cli
