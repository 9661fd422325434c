// Recorded robot logs without ROS: MCAP (ROS 2's default storage), rosbag2 sqlite3 and ROS 1
// bags are read (Sequence::openLog in sequence.hpp gives a log's stereo frames); depth is
// written back into MCAP with ros2msg schemas (DepthLogWriter). Readers follow the formats'
// specifications; messages are sensor_msgs/Image (mono8, mono16, rgb8, bgr8) and
// sensor_msgs/CompressedImage (png, jpeg), in ROS 2 CDR or ROS 1 serialisation.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "curvestereo/depth_views.hpp"
#include "curvestereo/rig.hpp"
#include "curvestereo/sequence.hpp"
#include "curvestereo/stereo.hpp"

namespace cs {

struct LogTopic {
  std::string name, type;
  std::string serialisation;  // "cdr" (ROS 2) or "ros1"
  uint64_t messages = 0;
  int64_t firstNs = 0, lastNs = 0;  // log (receive) times
};

struct LogInfo {
  std::string format;  // "MCAP, zstd chunks", "ROS 1 bag 2.0, bz2 chunks", "rosbag2 sqlite3"
  std::vector<LogTopic> topics;
  uint64_t messages = 0;
  int64_t startNs = 0, endNs = 0;
  std::string cut;  // where a log cut short ends ("" when whole)
};

// Lists a log's topics (reads every message's record, not its pixels). path: an .mcap, a ROS
// 1 .bag, a rosbag2 .db3 or a rosbag2 folder (metadata.yaml). Throws cs::Error, one line.
LogInfo logInfo(const std::string& path);

// Depth into an MCAP file (profile ros2, CDR, ros2msg schemas embedded), one message per
// topic and frame, stamped with the frame's timestamp (header.stamp and log time):
//   PREFIX/depth              sensor_msgs/Image 32FC1, radial depth (m; NaN invalid, +inf far)
//   PREFIX/camera_info        sensor_msgs/CameraInfo of camera 0 (its fisheye model)
//   PREFIX/points             sensor_msgs/PointCloud2, organised H x W, x y z float32 (cam0)
//   PREFIX/confidence         sensor_msgs/Image 32FC1 in [0, 1]
//   PREFIX/depth_pinhole      sensor_msgs/Image 32FC1, REP-118 z-depth of a virtual pinhole
//   PREFIX/depth_pinhole/camera_info   (both only with DepthLogOptions::pinhole)
struct DepthLogOptions {
  std::string compression = "zstd";  // "zstd", "lz4" or "none"
  std::string topicPrefix = "/curvestereo";
  std::string frameId = "cam0";
  float minConfidence = 0.f;  // points below it become NaN (the cloud keeps its grid)
  bool pinhole = false;
  PinholeView pinholeView;
  DepthSampling sampling = DepthSampling::Nearest;
  uint64_t chunkBytes = 4 << 20;  // a chunk is closed when it holds this much
};

class McapWriter;

class DepthLogWriter {
 public:
  // Throws cs::Error when the file cannot be created or an option is out of range.
  DepthLogWriter(const std::string& path, const Rig& rig, const DepthLogOptions& options = {});
  ~DepthLogWriter();  // closes (errors then only on stderr: call close() to see them)
  DepthLogWriter(const DepthLogWriter&) = delete;
  DepthLogWriter& operator=(const DepthLogWriter&) = delete;
  void write(int64_t stampNs, const DepthResult& result);
  // Writes the summary and footer. Frames written before an error elsewhere stay readable:
  // each chunk is complete once written, and readers scan a file without a summary.
  void close();
  uint64_t frames() const { return frames_; }

 private:
  std::unique_ptr<McapWriter> mcap_;
  Rig rig_;
  DepthLogOptions options_;
  uint16_t depth_ = 0, info_ = 0, points_ = 0, confidence_ = 0, pinholeDepth_ = 0, pinholeInfo_ = 0;
  uint64_t frames_ = 0;
};

// The stereo images of a sequence into an MCAP file (two sensor_msgs topics, profile ros2,
// CDR), stamped with each frame's timestamp: for tests and examples, and to turn image
// folders into a log. format: "raw" (sensor_msgs/Image mono8, or mono16 for 16-bit PNGs)
// or "png" (sensor_msgs/CompressedImage holding each PNG file's bytes).
struct ImageLogOptions {
  std::string leftTopic = "/cam0/image_raw", rightTopic = "/cam1/image_raw";
  std::string format = "raw";
  std::string compression = "zstd";
  uint64_t chunkBytes = 4 << 20;
};
void writeImageLog(const std::string& path, const Sequence& sequence, const ImageLogOptions& options = {});

}  // namespace cs
