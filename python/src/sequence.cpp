// Sequences in the Python module: curvestereo.Sequence (a recording's frame list, images
// read one frame at a time) and Frame, and the pose argument of Stereo.next.
//
//   seq = curvestereo.Sequence("seq/")       # cs::Sequence::open
//   for f in seq:                             # a Frame; f.left / f.right read on first use
//       r = stereo.next(f.left, f.right, pose=f.pose)
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cmath>
#include <filesystem>
#include <sstream>

#include "binding.hpp"
#include "curvestereo/log.hpp"
#include "curvestereo/sequence.hpp"

namespace cs::py {

namespace {

using Path = std::filesystem::path;

std::string shapeText(const pb::array& a) {
  std::string s = "(";
  for (pb::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

using DoubleArray = pb::array_t<double, pb::array::c_style | pb::array::forcecast>;

// Numbers only (not strings, objects or booleans), as float64; nullopt otherwise.
std::optional<DoubleArray> numbers(pb::handle obj) {
  const pb::array raw = pb::array::ensure(obj);
  if (!raw || std::string("iuf").find(raw.dtype().kind()) == std::string::npos) return std::nullopt;
  DoubleArray a = DoubleArray::ensure(raw);
  if (!a) return std::nullopt;
  return a;
}

std::string typeName(pb::handle v) { return Py_TYPE(v.ptr())->tp_name; }

// R must be a rotation: a pose from another convention (a 3 x 4 projection, a scaled or
// transposed matrix) would be silently wrong for the motion between frames.
void checkRotation(const Eigen::Matrix3d& R) {
  const double orthogonality = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (!(orthogonality < 1e-3) || !(R.determinant() > 0))
    throw Error("pose: R is not a rotation (R^T R must be the identity within 1e-3 and det R = +1)");
}

constexpr const char* kPoseForms = "None, a 4 x 4 array (T_world_cam0) or an (R, t) pair (3 x 3, 3)";

}  // namespace

std::optional<Pose> poseFrom(pb::handle obj) {
  if (obj.is_none()) return std::nullopt;
  Pose pose;
  if ((pb::isinstance<pb::tuple>(obj) || pb::isinstance<pb::list>(obj)) && pb::len(obj) == 2) {
    const pb::sequence pair = pb::reinterpret_borrow<pb::sequence>(obj);
    const std::optional<DoubleArray> Ra = numbers(pair[0]), ta = numbers(pair[1]);
    if (!Ra || Ra->ndim() != 2 || Ra->shape(0) != 3 || Ra->shape(1) != 3)
      throw Error("pose: R of an (R, t) pair must be a 3 x 3 array of numbers" +
                  (Ra ? ", got shape " + shapeText(*Ra) : ", got " + typeName(pair[0])));
    if (!ta || ta->size() != 3 || ta->ndim() > 2)
      throw Error("pose: t of an (R, t) pair must hold 3 numbers" +
                  (ta ? ", got shape " + shapeText(*ta) : ", got " + typeName(pair[1])));
    const DoubleArray &R = *Ra, &t = *ta;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) pose.R(r, c) = R.at(r, c);
      pose.t[r] = t.data()[r];
    }
  } else {
    const std::optional<DoubleArray> Ta = numbers(obj);
    if (!Ta) throw Error(std::string("pose must be ") + kPoseForms + ", got " + typeName(obj));
    const DoubleArray& T = *Ta;
    if (T.ndim() != 2 || T.shape(0) != 4 || T.shape(1) != 4)
      throw Error(std::string("pose must be ") + kPoseForms + ", got an array of shape " + shapeText(T));
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) pose.R(r, c) = T.at(r, c);
      pose.t[r] = T.at(r, 3);
    }
    if (T.at(3, 0) != 0 || T.at(3, 1) != 0 || T.at(3, 2) != 0 || T.at(3, 3) != 1)
      throw Error("pose: the last row of a 4 x 4 pose (T_world_cam0) must be [0, 0, 0, 1]");
  }
  if (!pose.R.allFinite() || !pose.t.allFinite()) throw Error("pose: contains NaN or infinite values");
  checkRotation(pose.R);
  return pose;
}

SequenceOptions sequenceOptions(pb::object poses, double pairToleranceMs, double poseToleranceMs) {
  SequenceOptions options;
  options.pairToleranceMs = pairToleranceMs;
  options.poseToleranceMs = poseToleranceMs;
  if (!poses.is_none()) options.poses = poses.cast<Path>().string();
  return options;
}

size_t frameIndex(long long i, size_t n) {
  const long long count = (long long)n;
  if (i < 0) i += count;
  if (i < 0 || i >= count)
    throw pb::index_error("frame index out of range (the sequence has " + std::to_string(count) + ")");
  return size_t(i);
}

pb::array poseArray(const Pose& pose) {
  pb::array a = pb::array_t<double>({4, 4});
  double* o = static_cast<double*>(a.mutable_data());
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) o[4 * r + c] = r < 3 ? (c < 3 ? pose.R(r, c) : pose.t[r]) : (c == 3 ? 1.0 : 0.0);
  return a;
}

namespace {

// One frame of a PySequence: the sequence's frame list is shared, the images are read on
// first use of left or right (both at once) and kept by this object.
struct PyFrame {
  std::shared_ptr<const Sequence> sequence;
  size_t index = 0;
  pb::object left = pb::none(), right = pb::none();

  const SequenceFrame& frame() const { return sequence->frames()[index]; }
  void load() {
    if (!left.is_none()) return;
    ImageF l, r;
    {
      pb::gil_scoped_release nogil;  // PNG decoding
      sequence->load(index, l, r);
    }
    left = floatArray(std::move(l));
    right = floatArray(std::move(r));
  }
};

class PySequence {
 public:
  PySequence(pb::handle source, pb::object poses, double pairToleranceMs, double poseToleranceMs) {
    const SequenceOptions options = sequenceOptions(poses, pairToleranceMs, poseToleranceMs);
    if (!(pairToleranceMs >= 0) || !(poseToleranceMs >= 0))
      throw Error("Sequence: pair_tolerance_ms and pose_tolerance_ms must be >= 0");
    // A (left, right) pair of folders or globs: the library's "LEFT,RIGHT".
    if (pb::isinstance<pb::tuple>(source) || pb::isinstance<pb::list>(source)) {
      if (pb::len(source) != 2) throw Error("Sequence: source must be a path or a (left, right) pair of folders");
      const pb::sequence pair = pb::reinterpret_borrow<pb::sequence>(source);
      source_ = pair[0].cast<Path>().string() + "," + pair[1].cast<Path>().string();
    } else {
      source_ = source.cast<Path>().string();
    }
    pb::gil_scoped_release nogil;  // a long recording's listing takes a moment
    sequence_ = std::make_shared<const Sequence>(Sequence::open(source_, options));
  }

  // A recorded log's frames (Sequence::openLog); source is "LOG:LEFT,RIGHT" for the repr.
  static PySequence fromLog(const Path& path, const std::pair<std::string, std::string>& topics, pb::object poses,
                            double pairToleranceMs, double poseToleranceMs) {
    const SequenceOptions options = sequenceOptions(poses, pairToleranceMs, poseToleranceMs);
    PySequence s;
    s.source_ = path.string() + ":" + topics.first + "," + topics.second;
    pb::gil_scoped_release nogil;  // reads every message's header
    s.sequence_ =
        std::make_shared<const Sequence>(Sequence::openLog(path.string(), topics.first, topics.second, options));
    return s;
  }

  size_t size() const { return sequence_->frames().size(); }
  PyFrame at(long long i) const { return PyFrame{sequence_, frameIndex(i, size())}; }
  const Sequence& sequence() const { return *sequence_; }
  const std::string& source() const { return source_; }

 private:
  PySequence() = default;
  std::string source_;
  std::shared_ptr<const Sequence> sequence_;
};

// A DepthResult view of a Python Result's arrays, for DepthLogWriter (copies: the writer
// serialises them anyway).
DepthResult depthFromResult(const Result& r) {
  using F32 = pb::array_t<float, pb::array::c_style | pb::array::forcecast>;
  const F32 depth = F32::ensure(r.depth), points = F32::ensure(r.points);
  if (!depth || depth.ndim() != 2) throw Error("DepthLogWriter.write: result.depth must be an H x W array");
  const int h = int(depth.shape(0)), w = int(depth.shape(1));
  if (!points || points.ndim() != 3 || points.shape(0) != h || points.shape(1) != w || points.shape(2) != 3)
    throw Error("DepthLogWriter.write: result.points must be H x W x 3, as depth");
  DepthResult out;
  out.depth.radial = ImageF(w, h);
  std::copy(depth.data(), depth.data() + depth.size(), out.depth.radial.data.begin());
  out.depth.points = Image<Point3f>(w, h);
  for (size_t i = 0; i < out.depth.points.size(); ++i)
    out.depth.points.data[i] = {points.data()[3 * i], points.data()[3 * i + 1], points.data()[3 * i + 2]};
  if (!r.confidence.is_none()) {
    const F32 c = F32::ensure(r.confidence);
    if (!c || c.ndim() != 2 || c.shape(0) != h || c.shape(1) != w)
      throw Error("DepthLogWriter.write: result.confidence must be H x W, as depth");
    out.confidence = ImageF(w, h);
    std::copy(c.data(), c.data() + c.size(), out.confidence.data.begin());
  }
  return out;
}

class PyDepthLogWriter {
 public:
  PyDepthLogWriter(const Path& path, const Rig& rig, const std::string& compression, float minConfidence,
                   pb::object pinhole, const std::string& topicPrefix, const std::string& frameId) {
    DepthLogOptions o;
    o.compression = compression;
    o.minConfidence = minConfidence;
    o.topicPrefix = topicPrefix;
    o.frameId = frameId;
    if (!pinhole.is_none()) {  // horizontal FOV in degrees, or (fov, width, height)
      o.pinhole = true;
      if (pb::isinstance<pb::tuple>(pinhole)) {
        const auto t = pinhole.cast<std::tuple<double, int, int>>();
        o.pinholeView = PinholeView::fromFov(std::get<0>(t), std::get<1>(t), std::get<2>(t));
      } else {
        o.pinholeView = PinholeView::fromFov(pinhole.cast<double>(), rig.cam0.width, rig.cam0.height);
      }
    }
    writer_ = std::make_unique<DepthLogWriter>(path.string(), rig, o);
  }
  void write(int64_t stampNs, const Result& r) {
    if (!writer_) throw Error("DepthLogWriter is closed");
    const DepthResult d = depthFromResult(r);
    pb::gil_scoped_release nogil;
    writer_->write(stampNs, d);
  }
  void close() {
    if (!writer_) return;
    writer_->close();
    frames_ = writer_->frames();
    writer_.reset();
  }
  uint64_t frames() const { return writer_ ? writer_->frames() : frames_; }

 private:
  std::unique_ptr<DepthLogWriter> writer_;
  uint64_t frames_ = 0;
};

pb::dict logInfoDict(const Path& path) {
  LogInfo info;
  {
    pb::gil_scoped_release nogil;
    info = logInfo(path.string());
  }
  pb::list topics;
  for (const LogTopic& t : info.topics)
    topics.append(pb::dict(pb::arg("name") = t.name, pb::arg("type") = t.type,
                           pb::arg("serialisation") = t.serialisation, pb::arg("messages") = t.messages,
                           pb::arg("first_ns") = t.firstNs, pb::arg("last_ns") = t.lastNs));
  return pb::dict(pb::arg("format") = info.format, pb::arg("messages") = info.messages,
                  pb::arg("start_ns") = info.startNs, pb::arg("end_ns") = info.endNs, pb::arg("cut") = info.cut,
                  pb::arg("topics") = topics);
}

struct FrameIterator {
  PySequence sequence;
  size_t next = 0;
};

// Sequence.read_ahead(): frames read on background threads (SequenceReader) while the caller
// solves, each Frame handed out with its images. Unlike iteration, which reads a frame when
// its images are used, this reads every frame, in order.
class ReadAhead {
 public:
  ReadAhead(const PySequence& s, int threads)
      : sequence_(s), reader_(std::make_unique<SequenceReader>(s.sequence(), threads)) {}
  PyFrame next() {
    size_t index = 0;
    ImageF l, r;
    bool more = false;
    {
      pb::gil_scoped_release nogil;  // waits for the readers, which need no Python
      more = reader_->next(index, l, r);
    }
    if (!more) throw pb::stop_iteration();
    PyFrame f = sequence_.at((long long)index);
    f.left = floatArray(std::move(l));
    f.right = floatArray(std::move(r));
    return f;
  }
  const SequenceReader& reader() const { return *reader_; }

 private:
  PySequence sequence_;  // holds the frame list the readers use (destroyed after them)
  std::unique_ptr<SequenceReader> reader_;
};

}  // namespace

void bindSequence(pb::module_& m) {
  pb::class_<PyFrame>(m, "Frame",
                      "One stereo frame of a Sequence. left and right are read from their files on first use "
                      "(float32 gray in [0, 1], as read_image), then kept by this object.")
      .def_property_readonly(
          "index", [](const PyFrame& f) { return f.index; }, "Position in the sequence.")
      .def_property_readonly(
          "timestamp_ns", [](const PyFrame& f) { return f.frame().timestampNs; }, "Camera 0's timestamp, nanoseconds.")
      .def_property_readonly(
          "left",
          [](PyFrame& f) {
            f.load();
            return f.left;
          },
          "Camera 0's image, float32 H x W in [0, 1] (read on first use).")
      .def_property_readonly(
          "right",
          [](PyFrame& f) {
            f.load();
            return f.right;
          },
          "Camera 1's image, float32 H x W in [0, 1] (read on first use).")
      .def_property_readonly(
          "pose",
          [](const PyFrame& f) -> pb::object {
            if (!f.frame().hasPose) return pb::none();
            return poseArray(f.frame().pose);
          },
          "T_world_cam0 as a 4 x 4 float64 array (what Stereo.next takes), or None when the frame has no pose.")
      .def_property_readonly(
          "left_path", [](const PyFrame& f) { return f.frame().leftPath; }, "Camera 0's image file.")
      .def_property_readonly(
          "right_path", [](const PyFrame& f) { return f.frame().rightPath; }, "Camera 1's image file.")
      .def("__repr__", [](const PyFrame& f) {
        return "<curvestereo.Frame " + std::to_string(f.index) + " t=" + std::to_string(f.frame().timestampNs) + " ns" +
               (f.frame().hasPose ? ", posed" : "") + ">";
      });

  pb::class_<FrameIterator>(m, "_FrameIterator")
      .def("__iter__", [](FrameIterator& it) -> FrameIterator& { return it; })
      .def("__next__", [](FrameIterator& it) {
        if (it.next >= it.sequence.size()) throw pb::stop_iteration();
        return it.sequence.at((long long)it.next++);
      });

  pb::class_<ReadAhead>(m, "_ReadAhead")
      .def("__iter__", [](ReadAhead& it) -> ReadAhead& { return it; })
      .def("__next__", &ReadAhead::next)
      .def_property_readonly(
          "threads", [](const ReadAhead& r) { return r.reader().threads(); }, "Background reader threads.")
      .def_property_readonly(
          "first_wait_ms", [](const ReadAhead& r) { return r.reader().firstWaitMs(); },
          "How long the first frame was waited for (ms).")
      .def_property_readonly(
          "waited_ms", [](const ReadAhead& r) { return r.reader().waitedMs(); },
          "How long the frames after the first were waited for, in all (ms): the reading left on the caller's path.")
      .def_property_readonly(
          "read_ms", [](const ReadAhead& r) { return r.reader().readMs(); },
          "How long the frames handed out took to read on the background threads, in all (ms).");

  pb::class_<PySequence>(m, "Sequence",
                         R"doc(A recorded stereo sequence: its frame list, images read one frame at a time.

Sequence(source, poses=None, pair_tolerance_ms=1.0, pose_tolerance_ms=5.0)

source: an ASL / EuRoC folder (the folder holding mav0/, or mav0/ itself: cam0/data.csv,
cam0/data/, cam1 alike; its poses_cam0.csv is used unless poses is given), or two folders
of PNG images (or glob patterns) as "LEFT,RIGHT" or a (left, right) pair, paired by
sorted name. poses: a poses file, T_world_cam0 per timestamp (EuRoC CSV
"t_ns,px,py,pz,qx,qy,qz,qw" or TUM "t_s tx ty tz qx qy qz qw"). pair_tolerance_ms: the
largest left/right timestamp difference of an ASL pair. pose_tolerance_ms: how near a
pose must be to a frame's timestamp to be attached (no interpolation).

len(seq), seq[i] (negative from the end) and iteration give Frame objects; their
images are read when first used. Frames that could not be paired, or were left without a
pose, are listed in .warnings. Raises curvestereo.Error naming the file and the line.

    seq = curvestereo.Sequence("seq/")
    stereo = curvestereo.Stereo(curvestereo.load_calibration("seq/camchain.yaml"))
    for f in seq:
        r = stereo.next(f.left, f.right, pose=f.pose))doc")
      .def(pb::init<pb::handle, pb::object, double, double>(), pb::arg("source"), pb::arg("poses") = pb::none(),
           pb::arg("pair_tolerance_ms") = 1.0, pb::arg("pose_tolerance_ms") = 5.0)
      .def_static("from_log", &PySequence::fromLog, pb::arg("path"), pb::arg("topics"), pb::arg("poses") = pb::none(),
                  pb::arg("pair_tolerance_ms") = 1.0, pb::arg("pose_tolerance_ms") = 5.0,
                  "A recorded log's stereo frames: an MCAP file, a ROS 1 bag (2.0), a rosbag2 .db3 or bag folder; "
                  "topics = (left, right), two sensor_msgs/Image or CompressedImage topics paired by header.stamp "
                  "within pair_tolerance_ms. A log cut short is read up to the cut (.warnings says where).")
      .def("__len__", &PySequence::size)
      .def("__getitem__", &PySequence::at, pb::arg("index"))
      .def("__iter__", [](const PySequence& s) { return FrameIterator{s}; })
      .def(
          "read_ahead", [](const PySequence& s, int threads) { return std::make_unique<ReadAhead>(s, threads); },
          pb::arg("threads") = 0,
          "Iterates every frame in order, read ahead on `threads` background threads (0: one per four cores, 1 to "
          "4) while the caller solves the one before; each Frame comes with its images. A frame that cannot be read "
          "raises curvestereo.Error at its turn, and iteration ends there. .waited_ms says how long the caller "
          "waited for frames.")
      .def_property_readonly(
          "warnings", [](const PySequence& s) { return s.sequence().warnings(); },
          "Notes to show, one line each: frames that could not be paired, frames without a pose although poses "
          "were given, folder pairs whose names differ.")
      .def_property_readonly(
          "summary", [](const PySequence& s) { return s.sequence().summary(); },
          "One line, e.g. '16 stereo frames (ASL, 16 with poses); 0 unpaired'.")
      .def_property_readonly(
          "timestamps_ns",
          [](const PySequence& s) {
            const auto& frames = s.sequence().frames();
            pb::array_t<int64_t> a(pb::ssize_t(frames.size()));
            for (size_t i = 0; i < frames.size(); ++i) a.mutable_data()[i] = frames[i].timestampNs;
            return a;
          },
          "Every frame's timestamp (int64 nanoseconds), without reading an image.")
      .def_property_readonly(
          "source", [](const PySequence& s) { return s.source(); }, "The source as opened.")
      .def("__repr__", [](const PySequence& s) { return "<curvestereo.Sequence " + s.sequence().summary() + ">"; });

  m.def("log_info", &logInfoDict, pb::arg("path"),
        "A recorded log's format, topics (name, type, serialisation, messages, first_ns, last_ns), message "
        "count, time range (log times, ns) and where it was cut short ('' when whole).");

  pb::class_<PyDepthLogWriter>(m, "DepthLogWriter",
                               R"doc(Depth into an MCAP log (profile ros2, CDR, ros2msg schemas embedded).

DepthLogWriter(path, rig, compression="zstd", min_confidence=0.0, pinhole=None,
               topic_prefix="/curvestereo", frame_id="cam0")

write(timestamp_ns, result) adds a frame: PREFIX/depth (sensor_msgs/Image 32FC1, radial
metres), PREFIX/camera_info, PREFIX/points (organised PointCloud2), PREFIX/confidence (32FC1)
and, with pinhole = FOV or (FOV, W, H), PREFIX/depth_pinhole (REP-118 z-depth) with its
camera_info. close() (or leaving a with block) writes the summary.

    with curvestereo.DepthLogWriter("depth.mcap", rig) as out:
        for f in curvestereo.Sequence.from_log("run.mcap", ("/cam0/image_raw", "/cam1/image_raw")):
            out.write(f.timestamp_ns, stereo.next(f.left, f.right)))doc")
      .def(pb::init<const Path&, const Rig&, const std::string&, float, pb::object, const std::string&,
                    const std::string&>(),
           pb::arg("path"), pb::arg("rig"), pb::arg("compression") = "zstd", pb::arg("min_confidence") = 0.f,
           pb::arg("pinhole") = pb::none(), pb::arg("topic_prefix") = "/curvestereo", pb::arg("frame_id") = "cam0")
      .def("write", &PyDepthLogWriter::write, pb::arg("timestamp_ns"), pb::arg("result"))
      .def("close", &PyDepthLogWriter::close)
      .def_property_readonly("frames", &PyDepthLogWriter::frames, "Frames written so far.")
      .def("__enter__", [](PyDepthLogWriter& w) -> PyDepthLogWriter& { return w; })
      .def("__exit__", [](PyDepthLogWriter& w, pb::object, pb::object, pb::object) { w.close(); });
}

}  // namespace cs::py
