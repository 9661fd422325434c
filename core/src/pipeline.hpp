// The per-frame algorithm (docs/design.md "Per frame"), written once against Backend.
#pragma once
#include <algorithm>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include "curvestereo/backend.hpp"
#include "curvestereo/params.hpp"
#include "curvestereo/pipeline_params.hpp"
#include "curvestereo/rig.hpp"
#include "curvestereo/stereo.hpp"
#include "plain_fill.hpp"

namespace cs {

namespace detail {
struct DeviceIO;
}

// Makes img a w x h image for the next frame to overwrite: its storage stays when the size
// already matches (no allocation, no zero fill). Returns its first element.
template <class T>
T* fitImage(Image<T>& img, int w, int h) {
  img.width = w;
  img.height = h;
  img.data.resize(size_t(w) * size_t(h));
  return img.data.data();
}

// A frame of a sequence is cold (the full schedule, as a pair) or warm (from the previous
// frame's estimate carried into its view: no levels above the band sweep's, no full sweep),
// with or without the temporal filter. Each kind is its own recorded frame
// (Backend::beginFrame's slot).
// A frame's input image as the caller holds it: floats in [0, 1] (checked for NaN and
// infinities as they upload) or a camera's 8-bit samples (Backend::uploadBytes), which
// cross to a GPU at a quarter of the bytes. The caller has checked its size.
struct InputImage {
  const float* floats = nullptr;
  const uint8_t* bytes = nullptr;
  InputImage(const ImageF& image) : floats(image.data.data()) {}
  InputImage(const ImageU8& image) : bytes(image.data.data()) {}
};

struct FrameKind {
  bool warm = false, filter = false;
  int slot() const { return (warm ? 2 : 0) + (filter ? 1 : 0); }
};

class Pipeline {
 public:
  // Allocates every buffer of every level once. userMask (optional, full resolution)
  // restricts the solve; setPose() must be called before run().
  // finishes: the frame ends with Backend::finishResult (unsolved pixels NaN in every
  // output, the valid mask, z). Only lrCheck's other direction does not: the round trip reads
  // its warp as solved, and it has no user.
  Pipeline(Backend& backend, const Rig& rig, const Params& params, const ImageU8& userMask, bool finishes = true);
  // What the constructor allocates on the backend for the rig's frame.
  static unsigned long long bufferBytes(const Rig& rig, const Params& params);
  // A lower bound of bufferBytes without the sweep's volumes, whose size needs a scan of the
  // camera (seconds for a frame of tens of thousands of pixels a side): refuses such a frame
  // at once.
  static unsigned long long bufferBytesBeforeSweep(const Rig& rig, const Params& params);

  // Recomputes the per-rig fields of every level on the backend (a moving camera calls
  // this whenever the relative pose changes).
  void setPose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t);
  // Replaces the user's mask (empty: none); takes effect with the next setPose().
  void setUserMask(const ImageU8& userMask);

  // Which of the optional outputs run() downloads; radial depth (and from it the valid
  // mask) always comes back. Skipping the rest saves most of a GPU frame's transfer time.
  struct Selection {
    bool disparity = true, warp = true, points = true, confidence = true;
  };
  void select(const Selection& selection) { selection_ = selection; }

  // One frame: uploads the images, solves, finishes (Backend::finishResult) and downloads
  // into `out`: depth.radial and out.valid, the selected disparity, warp, confidence and
  // depth.points with depth.z (the others become empty images), and out.stages (empty
  // unless `profile`: time each stage, synchronising at each boundary, instead of
  // replaying). Images of the right size keep their storage, so a caller reusing `out`
  // allocates nothing. The valid mask is not downloaded: finishResult leaves radial NaN
  // exactly where it is 0.
  void run(const InputImage& left, const InputImage& right, bool profile, const std::function<void(double)>& progress,
           DepthResult& out, FrameKind kind = {}, bool countConsistent = false);

  // --- sequences ---
  // Whether warm frames are possible: the band sweep's coarse level is where the carried
  // estimate enters (Params::warmStart).
  bool canWarmStart() const { return initialising() && sweep_.banded; }
  // Allocates the sequence's buffers on first use and forgets the carried state: the next
  // frame must be cold, and every frame is preceded by its setMotion().
  void resetSequence();
  // The motion of camera 0 since the previous frame (X_new = R X_prev + t); identity when
  // unknown. Uploaded outside the frame, so a replayed frame uses it.
  void setMotion(const Eigen::Matrix3d& R, const Eigen::Vector3d& t);
  // Makes the frame just solved the one the next frame carries (a failed warm frame is not
  // committed: it is solved again cold from the same state).
  void commitSequenceFrame();
  // The share of the sweep level's valid pixels whose left-right check passed in the frame
  // just solved (NaN without the initialiser): a warm frame's health, read at the sweep's
  // resolution (a sixteenth of the full frame's transfer with realtime).
  // Counted by run() when it was asked to (countConsistent), else NaN.
  double consistentShare() const;
  // Params::lrCheck: the share of the valid pixels (the mask at full resolution) whose round
  // trip passed in the frame just solved (NaN without lrCheck): the figure a real pair has
  // without ground truth. Counted by run(), from the round trip's error brought back with
  // the results.
  double roundTripShare() const;
  // The mean of the result's confidence over the field of view in the sequence frame just
  // solved (NaN when run() was not asked to count, or for a single pair): how well the
  // images agree with the estimate (the photometric term, the data residual after the last
  // warp) and how well it is supported (structure, the sweep's check), read from a copy of
  // the confidence at a sixteenth of the pixels.
  double meanConfidence() const;
  // Stereo's warm-failure check (Params::warmFailRatio): sequence frames then also
  // summarise the result's confidence for meanConfidence(). DeviceStereo has no check and
  // leaves it off, so its frames do none of that work. Before the first frame.
  void checkWarmFrames(bool on) { checksWarmFrames_ = on; }

  // For callers whose images are already on the backend's device (cs::cuda::DeviceStereo):
  // they fill `left` / `right` themselves, call runOnDevice(), which issues (or replays)
  // the frame with no host transfer of images and, but for plainFill's one wait for the
  // host's plane fits, no synchronisation, and read the results from the other buffers on
  // the device.
  detail::DeviceIO deviceIO() const;  // stereo_core.hpp
  void runOnDevice(FrameKind kind = {});

 private:
  struct Level {
    LevelSize size;
    Camera cam0, cam1;
    Buffer userMask;  // the user's mask at this level (or all ones)
    Buffer i0, i1, mask, trajectory, tensor, steps, w, tangent, scratch;
    // What the data term compares: i0, i1 normalised (3-ch moments as scratch), or i0, i1
    // themselves with the brightness data term (n0, n1 then alias them).
    Buffer n0, n1, moments;
    Buffer confidence;  // data-term weight from the initialiser (id -1 without one)
    PrimalDualBuffers pd;
    DataTermBuffers data;
  };

  // The plane-sweep initialiser: which level, its hypotheses, and its buffers.
  // With a band (Params::initBand) the full sweep runs one level coarser (and initialises
  // that level too) and `level`'s sweep scores only each pixel's band around its winners.
  struct Sweep {
    size_t level = 0;      // where its result initialises the solve
    SweepParams params{};  // params.t is t' (camera 0 as reference)
    Buffer volume;         // warped samples, then the aggregated costs (planes or band ch)
    Buffer costs;          // window costs (planes or band ch)
    Buffer best, other;
    bool banded = false;
    Buffer first;                // each pixel's first hypothesis (band sweep)
    SweepParams coarseParams{};  // the full sweep one level coarser (band sweep)
    Buffer coarseVolume, coarseCosts, coarseBest, coarseOther;
    bool warmBanded = false;  // a warm frame sweeps a narrower band (Params::warmBand)
    SweepParams warmParams{};
    Buffer warmVolume, warmCosts;
  };
  static double sweepQMax(const Eigen::Vector3d& tPrime, const Params& params);
  static int sweepPlanes(const Camera& cam, const Eigen::Vector3d& tPrime, const Params& params);
  void runCoarseSweep();
  void runSweep();
  void fullSweep(const Level& L, const SweepParams& p, const Buffer& volume, const Buffer& costs, const Buffer& best,
                 const Buffer& other);
  void bandSweep(const Level& L, const Buffer& coarseBest, const Buffer& coarseOther, float coarseScale,
                 const SweepParams& p, const Buffer& volume, const Buffer& costs);
  void checkSweep(Level& L, const SweepParams& p, const Buffer& best, const Buffer& other);
  bool normalising() const { return params_.dataTerm == Params::DataTerm::Normalised; }
  bool initialising() const { return params_.init == Params::Init::PlaneSweep; }

  // The count of the mask's valid pixels, downloaded into `counted` when it is negative.
  long long countMask(const Buffer& mask, long long& counted);
  void upload(const InputImage& left, const InputImage& right);
  void uploadImage(const Buffer& dst, const InputImage& image, const char* side);
  void issueSolve(const std::function<void(double)>& progress, FrameKind kind);
  void findPlainSupport();
  void planPlainFill();
  void issueFinish(FrameKind kind);
  void issueOrReplay(const std::function<void(double)>& progress, FrameKind kind);
  void recordOrReplay(int slot, const std::function<void(double)>& progress, const std::function<void()>& issue);
  // Every frame, warm ones too: a warm frame's brief solve does not keep the last frame's
  // planes (seqD1, CPU, 8 frames: warm tau>1 21.16 % without its own fill, 6.58 % cold).
  bool fillsPlains() const { return params_.plainFill; }
  size_t plainLevel() const { return std::min(size_t(params_.plainFillLevel), levels_.size() - 1); }
  void buildPyramid(size_t levels);
  void carryIntoCoarseSweep();
  ConfidenceParams confidenceTerms() const;
  void filterResult();
  void triangulate();
  void finishResult();
  void finishOutputs();
  void summariseConfidence();
  // Whether a frame of this kind summarises its confidence (meanConfidence): a sequence's
  // frame, with Stereo's warm-failure check on.
  bool summarises(FrameKind kind) const { return kind.filter && checksWarmFrames_; }
  void swapIntoReverse();
  void stage(const char* name);
  void initialiseLevel(size_t l);
  void startFromCoarser(size_t l);
  void solveLevel(Level& level, int warps, const std::function<void(int)>& warpDone);
  PrimalDualParams primalDualParams() const;
  void download(DepthResult& out, bool countConsistent, bool countConfidence);

  Backend& backend_;
  Params params_;
  Eigen::Vector3d tPrime_ = Eigen::Vector3d::Zero();
  std::vector<Level> levels_;
  Sweep sweep_;
  Buffer rawRight_, calibration_, radial_, points_;
  Buffer confidence_;  // the result's (resultConfidence), level 0
  bool finishes_ = true;
  Buffer valid_, z_;  // finishResult's (finishes_)
  // Params::lrCheck: the other direction's solve (camera 1 as the reference) on the same
  // backend, its frames recorded in slots of their own, and the round trip's error.
  std::unique_ptr<Pipeline> reverse_;
  int slotBase_ = 0;
  Buffer roundTripError_;
  bool profiling_ = false;
  bool warmFrame_ = false;  // the frame being issued is warm (issueSolve)
  bool checksWarmFrames_ = false;
  Selection selection_;
  // Params::plainFill: the support under each pixel of its level, the labels and planes the
  // host found (planPlainFill), and the host's copy of the support.
  Buffer plainSupport_, plainLabels_, plainPlanes_;
  Buffer planeConfidence_;  // level 0: fillPlanes' confidence of the filled pixels (id -1 without plainFill)
  std::vector<float> support_;
  PlainRays plainRays_;  // its level's rays (made by the first frame after setPose)
  // A sequence's state at level 0 (Backend::carryEstimate): `state` is the committed
  // frame's, `next` this frame's filtered result, `prior` the state carried into this
  // frame's view; `motion` the kMotionFloats of camera 0's motion. Created by resetSequence.
  Buffer state_, next_, prior_, motion_;
  // The result's confidence at level kSummaryLevel (summariseConfidence), for meanConfidence.
  Buffer confidenceSummary_;
  long long sweepMaskPixels_ = -1;    // valid pixels at the sweep's level (-1: not counted since setPose)
  long long maskPixels_ = -1;         // valid pixels at level 0 (roundTripShare; -1: not counted since setPose)
  long long summaryMaskPixels_ = -1;  // valid pixels at confidenceSummary_'s level (meanConfidence)
  // download()'s copies the shares are counted from
  std::vector<float> sweepConfidence_, roundTripErrors_, confidenceSummaries_;
  double consistentShare_ = std::numeric_limits<double>::quiet_NaN();
  double roundTripShare_ = std::numeric_limits<double>::quiet_NaN();
  double meanConfidence_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace cs
