// Rigs of N cameras (issue 32): load_rig, CameraRig, RigStereo, RigResult and its Panorama.
// The solves, the per-camera fusion and the panorama are the library's (RigStereo and
// rig_fusion.hpp), the same calls `curvestereo run --calib rig.yaml cam0.png ...` makes, so
// the module and the CLI give the same numbers for the same inputs.
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "binding.hpp"
#include "curvestereo/camera_rig.hpp"
#include "curvestereo/rig_fusion.hpp"
#include "curvestereo/rig_sequence.hpp"
#include "curvestereo/rig_stereo.hpp"

namespace cs::py {

namespace {

using Path = std::filesystem::path;

CameraRig loadRigFile(const Path& path) { return loadCameraRig(path.string()); }

// T_body_cam as a 4 x 4 float64 array (X_body = R X_cam + p), as Sequence poses are given.
pb::array bodyPoseArray(const BodyPose& pose) {
  pb::array_t<double> a({4, 4});
  double* o = a.mutable_data();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) o[4 * r + c] = r == 3 ? (c == 3 ? 1.0 : 0.0) : (c == 3 ? pose.p(r) : pose.R(r, c));
  return std::move(a);
}

pb::dict pairDict(const PairInfo& p) {
  pb::dict d;
  d["i"] = p.i;
  d["j"] = p.j;
  d["overlap_ij"] = p.overlapIJ;
  d["overlap_ji"] = p.overlapJI;
  d["baseline"] = p.baseline;
  return d;
}

pb::list pairList(const std::vector<PairInfo>& pairs) {
  pb::list out;
  for (const PairInfo& p : pairs) out.append(pairDict(p));
  return out;
}

std::vector<PairInfo> chosenPairs(const CameraRig& rig, int partners) {
  if (partners < 1 || partners > 8) throw Error("partners must be 1 to 8");
  return choosePairs(rig, partners);
}

// pairs=: None (each camera's best partners), the CLI's "0-1,1-2", or [(0, 1), (1, 2)]. The
// list is written as the CLI's text so that both are checked by the library's parsePairs.
std::vector<PairInfo> pairsFrom(const CameraRig& rig, pb::handle obj, int partners) {
  if (obj.is_none()) return chosenPairs(rig, partners);
  if (pb::isinstance<pb::str>(obj)) return parsePairs(rig, obj.cast<std::string>());
  std::string text;
  for (pb::handle item : obj) {
    const bool twoInts = pb::isinstance<pb::sequence>(item) && pb::len(item) == 2 &&
                         pb::isinstance<pb::int_>(item[pb::int_(0)]) && pb::isinstance<pb::int_>(item[pb::int_(1)]);
    if (!twoInts) throw Error("pairs must be a string such as '0-1,1-2' or a list of (i, j) camera indexes");
    const auto pair = pb::reinterpret_borrow<pb::sequence>(item);
    text += (text.empty() ? "" : ",") + std::to_string(pair[0].cast<int>()) + "-" + std::to_string(pair[1].cast<int>());
  }
  return parsePairs(rig, text);
}

Eigen::Vector3d centreFrom(pb::handle obj) {
  const auto a = pb::array_t<double, pb::array::c_style | pb::array::forcecast>::ensure(obj);
  if (!a || a.size() != 3 || a.ndim() != 1) throw Error("centre must hold 3 values (metres, in the body frame)");
  return {a.data()[0], a.data()[1], a.data()[2]};
}

pb::array vectorArray(const Eigen::Vector3d& v) {
  pb::array_t<double> a(3);
  std::copy(v.data(), v.data() + 3, a.mutable_data());
  return std::move(a);
}

std::string sizeText(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

// camera k's image as the library's float gray, at its camera's size.
ImageF cameraImage(pb::handle obj, const CameraRig& rig, int k) {
  const std::string which = "cam" + std::to_string(k) + " image";
  ImageF img = imageFromArray(obj, which.c_str());
  const Camera& cam = rig.cameras[size_t(k)];
  if (img.width != cam.width || img.height != cam.height)
    throw Error(which + " is " + sizeText(img.width, img.height) + ", its camera is " +
                sizeText(cam.width, cam.height));
  return img;
}

// ---------------------------------------------------------------- results

struct PyPanorama {
  pb::object range, grey, confidence;
  int width = 0;
  pb::object centre;  // float64 (3,)
};

// The panorama fusion of one RigStereo's results, kept for the next call with the same width
// and centre: the cameras' rays and the working memory are most of a fusion's setup. Shared
// by the results (a result may outlive its RigStereo); one fusion at a time.
struct PanoramaCache {
  std::string backend = "cpu";  // the RigStereo's, set when it is made
  std::mutex busy;
  std::unique_ptr<PanoramaFusion> fusion;
  Eigen::Vector3d centre = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());

  std::vector<PanoramaView> views;  // the RigStereo's, set when it is made

  Panorama fuse(const CameraRig& rig, const PanoramaFrame& frame, int width, const std::vector<DepthResult>& estimates,
                const std::vector<ImageF>& images, float minConfidence) {
    const std::lock_guard<std::mutex> lock(busy);
    if (!fusion || width != fusion->width() || frame.centre != centre) {
      fusion.reset();  // a width the fusion refuses leaves no stale one behind
      fusion = std::make_unique<PanoramaFusion>(rig, frame, width, views, std::vector<CameraRays>{}, backend);
      centre = frame.centre;
    }
    return fusion->fuse(estimates, images, minConfidence);
  }
};

// What the panorama is fused from: each solve's estimate on its window (RigResult::views, as
// the CLI fuses them) and the images; these stay for any number of panorama() calls.
struct RigFusionInput {
  CameraRig rig;
  std::vector<DepthResult> views;
  std::vector<ImageF> images;
  std::shared_ptr<PanoramaCache> cache;
};

struct PyRigResult {
  pb::list cameras;  // Result, one per camera
  pb::list solves;
  double totalMs = 0;
  std::shared_ptr<const RigFusionInput> input;

  PyPanorama panorama(int width, pb::handle centre, float minConfidence) const {
    if (!(minConfidence >= 0.f && minConfidence <= 1.f)) throw Error("min_confidence must be in [0, 1]");
    PanoramaFrame frame = panoramaFrame(input->rig);
    if (!centre.is_none()) frame.centre = centreFrom(centre);
    Panorama p;
    {
      pb::gil_scoped_release nogil;  // a forward projection of every camera's pixels
      p = input->cache->fuse(input->rig, frame, width, input->views, input->images, minConfidence);
    }
    return {floatArray(std::move(p.range)), floatArray(std::move(p.grey)), floatArray(std::move(p.confidence)), width,
            vectorArray(frame.centre)};
  }
};

pb::dict solveDict(const RigResult::Solve& s) {
  pb::dict d;
  d["reference"] = s.reference;
  d["other"] = s.other;
  d["ms"] = s.ms;
  d["cross_check_invalidated"] = s.crossCheckInvalidated;
  d["warm"] = s.warm;
  d["redone"] = s.redone;
  d["window"] = pb::make_tuple(s.window.x0, s.window.y0, s.window.width, s.window.height);
  return d;
}

// ---------------------------------------------------------------- the solver

// Keyword names that set the field of view themselves (dashes read as underscores).
bool setsFieldOfView(std::string key) {
  for (char& c : key)
    if (c == '-') c = '_';
  return key == "max_fov" || key == "max_fov_deg";
}

class PyRigStereo {
 public:
  PyRigStereo(const CameraRig& rig, const std::string& presetName, const std::string& backend, pb::handle pairs,
              int partners, double crossCheck, bool oneWay, pb::kwargs kwargs)
      : rig_(rig) {
    std::string backendSpec = backend;
    pb::dict overrides;
    bool fovGiven = false;
    for (auto item : kwargs) {
      const std::string key = pb::str(item.first);
      if (key == "device")  // as Stereo's: an index or a name substring
        backendSpec += ":" + std::string(pb::str(item.second));
      else
        overrides[item.first] = item.second;
      fovGiven = fovGiven || setsFieldOfView(key);
    }
    params_ = paramsFrom(presetName, overrides);
    // As the CLI: a lens wider than 180 degrees is solved over its whole image circle.
    if (!fovGiven) params_ = rigParams(rig_, params_);
    pairs_ = pairsFrom(rig_, pairs, partners);
    pb::gil_scoped_release nogil;  // one Stereo per direction of each pair: backends set up
    stereo_ = std::make_unique<RigStereo>(rig_, pairs_, params_, backendSpec);
    stereo_->setCrossCheck(crossCheck);
    stereo_->setOneWay(oneWay);
    crossCheck_ = crossCheck;
    panoramas_->backend = stereo_->backendName();
    panoramas_->views = stereo_->views();
  }

  PyRigResult compute(pb::handle imagesObj) {
    return solve(imagesObj, [&](const std::vector<ImageF>& images) { return stereo_->compute(images); });
  }

  // RigStereo::next: a frame of a sequence; pose: T_world_body (the rig's), as Stereo.next's.
  PyRigResult next(pb::handle imagesObj, pb::handle poseObj) {
    const std::optional<Pose> pose = poseFrom(poseObj);
    return solve(imagesObj,
                 [&](const std::vector<ImageF>& images) { return stereo_->next(images, pose ? &*pose : nullptr); });
  }

  void resetSequence() { stereo_->resetSequence(); }

  const CameraRig& rig() const { return rig_; }
  const Params& params() const { return params_; }
  const std::vector<PairInfo>& pairs() const { return pairs_; }
  double crossCheck() const { return crossCheck_; }
  std::string backendName() const { return stereo_->backendName(); }

 private:
  // One frame through `run` (compute or next), the GIL released, into Python's RigResult.
  template <class Run>
  PyRigResult solve(pb::handle imagesObj, Run&& run) {
    std::unique_lock<std::mutex> lock(busy_, std::try_to_lock);
    if (!lock.owns_lock()) throw Error("this RigStereo object is in use by another thread (use one per thread)");
    std::vector<ImageF> images = imagesFrom(imagesObj);
    RigResult r;
    {
      pb::gil_scoped_release nogil;
      r = run(images);
    }
    PyRigResult out;
    out.totalMs = r.totalMs;
    for (const RigResult::Solve& s : r.solves) out.solves.append(solveDict(s));
    auto input =
        std::make_shared<RigFusionInput>(RigFusionInput{rig_, std::move(r.views), std::move(images), panoramas_});
    for (DepthResult& camera : r.cameras) out.cameras.append(pb::cast(resultFromDepth(std::move(camera))));
    out.input = std::move(input);
    return out;
  }

  // One image per camera, in order, each at its camera's size.
  std::vector<ImageF> imagesFrom(pb::handle obj) const {
    const std::string count = std::to_string(rig_.size());
    if (pb::isinstance<pb::str>(obj) || !pb::isinstance<pb::sequence>(obj) || pb::isinstance<pb::array>(obj))
      throw Error("compute() takes a list of " + count + " images, one per camera in order");
    const auto seq = pb::reinterpret_borrow<pb::sequence>(obj);
    if (int(seq.size()) != rig_.size())
      throw Error("the rig has " + count + " cameras: compute() needs " + count +
                  " images, one per camera in order, got " + std::to_string(seq.size()));
    std::vector<ImageF> images;
    for (int k = 0; k < rig_.size(); ++k) images.push_back(cameraImage(seq[size_t(k)], rig_, k));
    return images;
  }

  CameraRig rig_;
  Params params_;
  std::vector<PairInfo> pairs_;
  double crossCheck_ = 0;
  std::unique_ptr<RigStereo> stereo_;
  std::mutex busy_;
  std::shared_ptr<PanoramaCache> panoramas_ = std::make_shared<PanoramaCache>();
};

void bindCameraRig(pb::module_& m) {
  pb::class_<CameraRig>(m, "CameraRig",
                        "A rig of N >= 2 cameras, each with its pose in one body frame (load_rig). Solve it with "
                        "RigStereo; rig.pair(i, j) is the stereo Rig of two of its cameras.")
      .def("__len__", &CameraRig::size, "The number of cameras.")
      .def_property_readonly(
          "cameras",
          [](const CameraRig& r) {
            pb::list out;
            for (const Camera& c : r.cameras) out.append(cameraDict(c));
            return out;
          },
          "Each camera as {'model', 'width', 'height', 'params'} (as Rig.cam0).")
      .def_property_readonly(
          "poses",
          [](const CameraRig& r) {
            pb::list out;
            for (const BodyPose& p : r.poses) out.append(bodyPoseArray(p));
            return out;
          },
          "Each camera's pose T_body_cam, 4 x 4 float64 (a point X in the camera's frame is R X + p in the body's).")
      .def_property_readonly(
          "centre", [](const CameraRig& r) { return vectorArray(r.centre()); },
          "The mean of the camera centres in the body frame (the panorama's default centre).")
      .def(
          "pairs", [](const CameraRig& r, int partners) { return pairList(chosenPairs(r, partners)); },
          pb::arg("partners") = 2,
          "The pairs RigStereo solves by default: each camera with its `partners` best partners (overlap times "
          "baseline). A list of {'i', 'j', 'overlap_ij', 'overlap_ji', 'baseline'}, i < j.")
      .def(
          "overlaps", [](const CameraRig& r) { return pairList(pairTable(r)); },
          "Every pair i < j with its overlaps (the share of camera i's view camera j sees, and the converse) and "
          "baseline in metres, as `curvestereo calib show` prints them; same dicts as pairs().")
      .def("pair", &pairRig, pb::arg("i"), pb::arg("j"),
           "The stereo Rig of cameras i (as cam0) and j (as cam1), for Stereo.")
      .def("__repr__", [](const CameraRig& r) {
        return "<curvestereo.CameraRig of " + std::to_string(r.size()) + " cameras, " +
               sizeText(r.cameras.front().width, r.cameras.front().height) + " " + r.cameras.front().modelName() + ">";
      });
}

}  // namespace

// One frame of a RigSequence: the images are read on first use of `images` and kept.
struct PyRigFrame {
  std::shared_ptr<const RigSequence> sequence;
  size_t index = 0;
  pb::object images = pb::none();

  const RigSequenceFrame& frame() const { return sequence->frames()[index]; }
  pb::object loaded() {
    if (!images.is_none()) return images;
    std::vector<ImageF> read;
    {
      pb::gil_scoped_release nogil;  // PNG decoding
      sequence->load(index, read);
    }
    pb::list list;
    for (ImageF& image : read) list.append(floatArray(std::move(image)));
    images = list;
    return images;
  }
};

class PyRigSequence {
 public:
  PyRigSequence(const std::filesystem::path& source, const CameraRig& rig, pb::object poses, double pairToleranceMs,
                double poseToleranceMs) {
    const SequenceOptions options = sequenceOptions(poses, pairToleranceMs, poseToleranceMs);
    pb::gil_scoped_release nogil;  // a long recording's listing takes a moment
    sequence_ = std::make_shared<const RigSequence>(RigSequence::open(source.string(), rig, options));
  }
  size_t size() const { return sequence_->frames().size(); }
  PyRigFrame at(long long i) const { return PyRigFrame{sequence_, frameIndex(i, size())}; }
  const RigSequence& sequence() const { return *sequence_; }

 private:
  std::shared_ptr<const RigSequence> sequence_;
};

struct RigFrameIterator {
  PyRigSequence sequence;
  size_t next = 0;
};

void bindRigSequence(pb::module_& m) {
  pb::class_<PyRigFrame>(m, "RigFrame",
                         "One frame of a RigSequence: one image per camera, read on first use of `images`.")
      .def_property_readonly(
          "index", [](const PyRigFrame& f) { return f.index; }, "Position in the sequence.")
      .def_property_readonly(
          "timestamp_ns", [](const PyRigFrame& f) { return f.frame().timestampNs; }, "Camera 0's timestamp, ns.")
      .def_property_readonly("images", &PyRigFrame::loaded,
                             "One float32 H x W image in [0, 1] per camera, in order (read on first use, then kept).")
      .def_property_readonly(
          "pose",
          [](const PyRigFrame& f) -> pb::object {
            if (!f.frame().hasPose) return pb::none();
            return poseArray(f.frame().bodyPose);
          },
          "The rig's pose T_world_body as a 4 x 4 float64 array (what RigStereo.next takes), from camera 0's in "
          "the poses file; None when the frame has none.")
      .def_property_readonly(
          "paths", [](const PyRigFrame& f) { return f.frame().paths; }, "The image files, one per camera.")
      .def("__repr__", [](const PyRigFrame& f) {
        return "<curvestereo.RigFrame " + std::to_string(f.index) + " t=" + std::to_string(f.frame().timestampNs) +
               " ns" + (f.frame().hasPose ? ", posed" : "") + ">";
      });
  pb::class_<RigFrameIterator>(m, "_RigFrameIterator")
      .def("__iter__", [](RigFrameIterator& it) -> RigFrameIterator& { return it; })
      .def("__next__", [](RigFrameIterator& it) {
        if (it.next >= it.sequence.size()) throw pb::stop_iteration();
        return it.sequence.at((long long)it.next++);
      });
  pb::class_<PyRigSequence>(m, "RigSequence",
                            R"doc(A rig's recorded sequence: an ASL / EuRoC folder with one cam<k> per camera.

RigSequence(source, rig, poses=None, pair_tolerance_ms=1.0, pose_tolerance_ms=5.0)

source: the folder holding mav0/ (or mav0/ itself) with cam0/data.csv ... cam<N-1>/data.csv
and their data/ folders, for the N cameras of `rig` (a CameraRig, load_rig). Camera k's
images are paired to camera 0's by timestamp (within pair_tolerance_ms); every image left
out is named in .warnings. poses: camera 0's poses (T_world_cam0; EuRoC CSV or TUM), by
default the folder's poses_cam0.csv; each frame's .pose is the rig's, T_world_body.

    rig = curvestereo.load_rig("rec/camchain.yaml")
    stereo = curvestereo.RigStereo(rig)
    for f in curvestereo.RigSequence("rec", rig):
        r = stereo.next(f.images, pose=f.pose))doc")
      .def(pb::init<const std::filesystem::path&, const CameraRig&, pb::object, double, double>(), pb::arg("source"),
           pb::arg("rig"), pb::arg("poses") = pb::none(), pb::arg("pair_tolerance_ms") = 1.0,
           pb::arg("pose_tolerance_ms") = 5.0)
      .def("__len__", &PyRigSequence::size)
      .def("__getitem__", &PyRigSequence::at, pb::arg("index"))
      .def("__iter__", [](const PyRigSequence& s) { return RigFrameIterator{s}; })
      .def_property_readonly(
          "warnings", [](const PyRigSequence& s) { return s.sequence().warnings(); },
          "Notes to show, one line each: images in no frame, frames without a pose although poses were given.")
      .def_property_readonly(
          "summary", [](const PyRigSequence& s) { return s.sequence().summary(); },
          "One line, e.g. '16 frames of 4 cameras (ASL, 16 with poses); 0 images unpaired'.")
      .def("__repr__",
           [](const PyRigSequence& s) { return "<curvestereo.RigSequence " + s.sequence().summary() + ">"; });
}

void bindRigs(pb::module_& m) {
  bindRigSequence(m);
  bindCameraRig(m);
  m.def("load_rig", &loadRigFile, pb::arg("path"),
        "Read an N-camera calibration as a CameraRig: a Kalibr camchain with cam0..camN-1 or a Basalt "
        "calibration.json with N cameras. The rig is validated (every camera overlaps another). Raises "
        "curvestereo.Error naming the file and the problem.");

  pb::class_<PyPanorama>(m, "Panorama",
                         "The equirectangular panorama around a rig, W x W/2: longitude -180 to +180 degrees left to "
                         "right, latitude +90 (up) at the top, longitude 0 along camera 0's axis.")
      .def_readonly("range", &PyPanorama::range,
                    "Metres from the centre, float32 H x W; +inf at infinity, NaN where no camera gave a depth.")
      .def_readonly("grey", &PyPanorama::grey, "The images' grey level in [0, 1], float32 H x W; NaN where no range.")
      .def_readonly("confidence", &PyPanorama::confidence,
                    "The best confidence among the fused estimates, float32 H x W; NaN where no range.")
      .def_readonly("width", &PyPanorama::width, "W (the height is W / 2).")
      .def_readonly("centre", &PyPanorama::centre, "The panorama's centre in the body frame, metres.");

  pb::class_<PyRigResult>(m, "RigResult", "One frame of a rig: every camera's depth, and the panorama on request.")
      .def_readonly("cameras", &PyRigResult::cameras,
                    "One Result per camera, in order: its radial depth from its own centre, fused from its pairs.")
      .def_readonly("solves", &PyRigResult::solves,
                    "Each pair direction solved: {'reference', 'other', 'window', 'ms', 'cross_check_invalidated', "
                    "'warm', 'redone'}; window: (x0, y0, width, height), the part of the reference's image solved "
                    "(the side its partner sees).")
      .def_readonly("total_ms", &PyRigResult::totalMs, "The solves and the per-camera fusion, milliseconds.")
      .def("panorama", &PyRigResult::panorama, pb::arg("width") = 2048, pb::arg("centre") = pb::none(),
           pb::arg("min_confidence") = 0.0f,
           R"doc(Fuse the solves' depths into an equirectangular Panorama, width x width/2.

The same fusion as `curvestereo run --calib rig.yaml ...`'s panorama_range.exr (width:
--panorama-width, even, 4 to 32768; min_confidence: --panorama-min-confidence, samples
below it are left out). centre: 3 values in the body frame, default the rig's centre. The
GIL is released while it runs. It runs on the RigStereo's backend; the fusion (the
cameras' rays and the backend's buffers) is kept by the RigStereo for the next call with the
same width and centre.)doc");

  pb::class_<PyRigStereo>(m, "RigStereo",
                          R"doc(The solver for a rig of N cameras: every pair solved both ways by Stereo,
each camera's estimates fused into its depth; panoramas from the RigResult.

RigStereo(rig, preset="realtime", backend="auto", *, pairs=None, partners=2,
cross_check=0.0, one_way=False, **params). rig: a CameraRig (load_rig). pairs: None (each
camera's `partners` best partners, as rig.pairs()), "0-1,1-2", or [(0, 1), (1, 2)].
cross_check: a tolerance in [0, 1] for the round trip between a pair's two directions (0:
off), as the CLI's --cross-check. one_way: each pair solved in one direction only, as
--one-way: half the solves, a little less accurate; beyond its own solve each camera's depth
is its partner's carried into it (no disparity or flow there). params: as Stereo's; unless
max_fov is given, the field of view widens to the widest lens, as the CLI does. Raises
curvestereo.Error for a bad preset, parameter, pair or backend.)doc")
      .def(pb::init<const CameraRig&, const std::string&, const std::string&, pb::handle, int, double, bool,
                    pb::kwargs>(),
           pb::arg("rig"), pb::arg("preset") = "realtime", pb::arg("backend") = "auto", pb::kw_only(),
           pb::arg("pairs") = pb::none(), pb::arg("partners") = 2, pb::arg("cross_check") = 0.0,
           pb::arg("one_way") = false)
      .def("compute", &PyRigStereo::compute, pb::arg("images"),
           "Solve one frame: images is a list with one 2-D image per camera, in order (uint8, uint16 or float32 "
           "in [0, 1], each at its camera's size; colour is converted as read_image does). Returns a RigResult. "
           "The GIL is released while the pairs are solved.")
      .def("next", &PyRigStereo::next, pb::arg("images"), pb::arg("pose") = pb::none(),
           "One frame of a sequence: as compute(), but every pair's direction continues its own sequence as "
           "Stereo.next does (warm start, temporal filter; each camera's Result tells warm / redone). pose: the "
           "rig's T_world_body (a 4x4 matrix or (R, t)), from which each camera's own pose follows; None when "
           "unknown. compute() in between does not disturb the sequence.")
      .def("reset_sequence", &PyRigStereo::resetSequence, "The next frame starts a new sequence (cold).")
      .def_property_readonly("rig", &PyRigStereo::rig, "The CameraRig.")
      .def_property_readonly(
          "pairs", [](const PyRigStereo& s) { return pairList(s.pairs()); },
          "The pairs solved, as rig.pairs() lists them.")
      .def_property_readonly(
          "params", [](const PyRigStereo& s) { return paramsToDict(s.params()); },
          "Every solver parameter in use, by the names RigStereo() takes.")
      .def_property_readonly("cross_check", &PyRigStereo::crossCheck, "The cross-check tolerance (0: off).")
      .def_property_readonly("backend", &PyRigStereo::backendName, "The backend in use: 'cpu', 'cuda' or 'vulkan'.")
      .def("__repr__", [](const PyRigStereo& s) {
        return "<curvestereo.RigStereo of " + std::to_string(s.rig().size()) + " cameras, " +
               std::to_string(s.pairs().size()) + " pairs, on " + s.backendName() + ">";
      });
}

}  // namespace cs::py
