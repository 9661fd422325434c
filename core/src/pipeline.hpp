// The per-frame algorithm (DESIGN.md "Per frame"), written once against Backend.
#pragma once
#include <functional>
#include <vector>

#include "curvestereo/backend.hpp"
#include "curvestereo/fields.hpp"
#include "curvestereo/params.hpp"
#include "curvestereo/rig.hpp"
#include "curvestereo/stereo.hpp"

namespace cs {

// Wall time per named stage. A stage ends when the next starts; the backend is
// synchronised at each boundary so queued GPU work is charged to its own stage.
class StageClock {
 public:
  explicit StageClock(Backend& backend) : backend_(backend) {}
  void start(const std::string& name);
  std::vector<StageTime> finish();

 private:
  Backend& backend_;
  std::vector<StageTime> stages_;
  std::string current_;
  double startedMs_ = 0;
};

class Pipeline {
 public:
  // Allocates every buffer of every level once; uploads the per-rig fields.
  Pipeline(Backend& backend, const Rig& rig, const Params& params, const RigFields& fields, const ImageU8& mask);

  struct Output {
    ImageF disparity;
    FlowImage warp;
    std::vector<StageTime> stages;
  };
  Output run(const ImageF& left, const ImageF& right, const std::function<void(double)>& progress);

 private:
  struct Level {
    LevelSize size;
    Buffer i0, i1, mask, trajectory, tensor, steps, w, tangent, scratch;
    PrimalDualBuffers pd;
    DataTermBuffers data;
  };

  void buildPyramid(const ImageF& left, const ImageF& right);
  void initialiseLevel(size_t l);
  void solveLevel(Level& level, const std::function<void(int)>& warpDone);
  PrimalDualParams primalDualParams() const;

  Backend& backend_;
  Params params_;
  std::vector<Level> levels_;
  Buffer rawRight_, calibration_;
  StageClock clock_;
};

}  // namespace cs
