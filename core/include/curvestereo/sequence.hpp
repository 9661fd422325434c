// Recorded stereo sequences: the frame list of an ASL/EuRoC folder or of two image folders,
// with optional per-frame poses. Opening only lists the frames (cheap even for thousands);
// images are read one frame at a time by load(), so a long recording never sits in memory.
#pragma once
#include <condition_variable>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "curvestereo/image.hpp"
#include "curvestereo/pose.hpp"

namespace cs {

struct SequenceOptions {
  // Left/right frames of an ASL folder are paired when their timestamps differ by at most
  // this: the two cameras of a rig are triggered together but logged with some jitter.
  double pairToleranceMs = 1.0;
  // A pose is attached to a frame when one lies within this of the frame's (cam0) timestamp.
  // No interpolation: a pose from another instant would be silently wrong for motion.
  double poseToleranceMs = 5.0;
  // Optional poses file (T_world_cam0 per timestamp), its format detected by content:
  //  - CSV "t_ns,px,py,pz,qx,qy,qz,qw", comma separated, '#' header lines (EuRoC style);
  //  - TUM trajectory text "t_seconds tx ty tz qx qy qz qw", space separated, '#' comments.
  // Empty: an ASL folder's poses_cam0.csv when it has one, else no poses.
  std::string poses;
};

struct SequenceFrame {  // one stereo frame, not yet read
  int64_t timestampNs = 0;
  // The image files; for a log, "LOG:TOPIC#N" (the topic's N-th message, counted from 0).
  std::string leftPath, rightPath;
  bool hasPose = false;
  Pose pose;  // T_world_cam0 when hasPose
};

class Sequence {
 public:
  // source: (a) an ASL/EuRoC folder: the folder holding mav0/, or mav0/ itself
  //             (cam0/data.csv "#timestamp [ns],filename" + cam0/data/<file>, cam1 alike);
  //             its poses_cam0.csv (next to mav0/ or in it) is used when options.poses is empty;
  //         (b) "LEFT,RIGHT", each a folder of PNG images or a glob pattern ("left/*.png,right/*.png"),
  //             paired by sorted name (natural order: "9.png" before "10.png"), the i-th left with
  //             the i-th right. A frame's timestamp is its left file's stem when every stem is an
  //             integer (ns), else index * 1e9 / 30 (with a note).
  // Throws cs::Error, one line naming the problem: a missing folder or data.csv, a malformed
  // data.csv line ("…/cam0/data.csv line 7: …"), no frames, left/right counts that differ in
  // (b), a malformed poses file, or a source that is neither (a) nor (b).
  static Sequence open(const std::string& source, const SequenceOptions& options = {});

  // The stereo frames of a recorded log (log.hpp: an MCAP file, a ROS 1 bag, a rosbag2 .db3
  // or bag folder): the messages of two sensor_msgs/Image or CompressedImage topics, paired by
  // header.stamp as ASL frames are (mutual nearest within options.pairToleranceMs); a frame's
  // timestamp is its left message's stamp. Opening reads every message's header (not its
  // pixels) and checks each one's encoding. A log cut short is read up to the cut, and a
  // warning says where it was cut. Throws cs::Error, one line naming the log, topic and
  // message: a missing topic (the log's image topics listed), a topic of another type, an
  // unsupported encoding, a corrupt record or a bad CRC.
  static Sequence openLog(const std::string& path, const std::string& leftTopic, const std::string& rightTopic,
                          const SequenceOptions& options = {});

  const std::vector<SequenceFrame>& frames() const { return frames_; }
  // Notes the caller should show, one line each, so that nothing is dropped silently: every
  // frame that could not be paired ("cam0 1000033333333.png: no cam1 frame within 1 ms"),
  // frames left without a pose although poses were given, folder pairs whose names differ.
  const std::vector<std::string>& warnings() const { return warnings_; }
  // "16 stereo frames (ASL, 16 with poses); 0 unpaired"
  std::string summary() const;

  // Reads frame i as float gray in [0, 1] (8/16-bit PNG; colour converted to Rec. 601 luma,
  // as the CLI does). Throws cs::Error naming the frame's index, timestamp and file when a
  // file is missing or unreadable, or when the two images differ in size.
  // A log's frames are decoded from their messages the same way (mono8 / mono16 as 8 / 16-bit
  // PNG samples, rgb8 / bgr8 to luma, png / jpeg CompressedImage decoded). Thread-safe.
  void load(size_t i, ImageF& left, ImageF& right) const;
  // Frame i as its files store it when both are 8-bit gray PNGs, what cameras give (Stereo
  // takes them as they are: a quarter of the bytes to move); false for any other frame (a
  // log's, 16-bit or colour files), which load() converts. Same errors; thread-safe.
  bool loadBytes(size_t i, ImageU8& left, ImageU8& right) const;

  struct LogFrames;  // a log's reader and message references (log_sequence.cpp)
  struct Stamped;

 private:
  void attachPoses(const std::string& path, double toleranceMs);
  void loadLog(size_t i, ImageF& left, ImageF& right) const;
  const SequenceFrame& frameAt(size_t i) const;  // frames_[i], or an error naming i
  static void pairLogFrames(Sequence& seq, LogFrames& log, std::vector<Stamped>& left, std::vector<Stamped>& right,
                            double toleranceMs);

  std::shared_ptr<const LogFrames> log_;  // set for a log
  std::vector<SequenceFrame> frames_;
  std::vector<std::string> warnings_;
  std::string kind_;  // "ASL", "folder pairs" or the log's format
  bool posesGiven_ = false;
  size_t unpaired_ = 0;  // frames of either camera without a partner
};

// A sequence's frames in order, read ahead on background threads: while the caller solves
// frame i, frames i+1 .. i+threads+1 are being read, so reading leaves the caller's critical
// path when it is faster than solving (a log's chunks and PNG files decode in parallel).
// Memory: about threads+2 frames' images.
class SequenceReader {
 public:
  // threads: background readers; 0 picks one per four hardware threads, 1 to 4. Frames
  // first .. end-1 are read (end past the last frame: to the last).
  explicit SequenceReader(const Sequence& sequence, int threads = 0, size_t first = 0, size_t end = SIZE_MAX);
  ~SequenceReader();  // stops the readers (frames being read are finished, not used)
  SequenceReader(const SequenceReader&) = delete;
  SequenceReader& operator=(const SequenceReader&) = delete;
  // The next frame into left/right and its index; false after the last. A frame that cannot
  // be read throws its load() error here, at its turn, after every frame before it.
  bool next(size_t& index, ImageF& left, ImageF& right);
  int threads() const { return int(workers_.size()); }
  // Time next() waited for frames (the reading left on the caller's path): for the first
  // (nothing to overlap with) and for all the others; and the time the frames handed out
  // took to read (on the background threads); all in ms.
  double firstWaitMs() const { return firstWaitMs_; }
  double waitedMs() const { return waitedMs_; }
  double readMs() const { return readMs_; }

 private:
  struct Slot;
  void work();

  const Sequence& sequence_;
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::map<size_t, Slot> slots_;                  // frames read, not yet handed out
  std::vector<std::pair<ImageF, ImageF>> spare_;  // images handed back, for the readers to reuse
  size_t nextToRead_ = 0, nextToHand_ = 0, end_ = 0, ahead_ = 0, handed_ = 0;
  bool stopping_ = false;
  double firstWaitMs_ = 0, waitedMs_ = 0, readMs_ = 0;
};

// One row of an ASL camera's data.csv.
struct AslRow {
  int64_t timestampNs = 0;
  std::string filename;
  int line = 0;  // 1-based line in the file, for messages
};
// Parses the text of an ASL data.csv ("#timestamp [ns],filename"); `name` names it in errors.
// Tolerates CRLF, a UTF-8 byte-order mark, spaces around fields, '#' header/comment lines and
// blank lines. Returns the rows sorted by timestamp. Throws cs::Error "NAME line N: ..." on a
// line that is not "integer,filename" or on a timestamp that repeats.
std::vector<AslRow> parseAslCsv(const std::string& text, const std::string& name = "data.csv");

// Reads a poses file (either format of SequenceOptions::poses) into timestamp (ns) -> pose.
// Throws cs::Error "FILE line N: ..." on a malformed line, non-finite values, a zero
// quaternion or a repeated timestamp. parsePoses does the same on text already read.
std::map<int64_t, Pose> readPoses(const std::string& path);
std::map<int64_t, Pose> parsePoses(const std::string& text, const std::string& name = "poses");

}  // namespace cs
