// Shared by the log fuzz targets (fuzz_log_mcap, fuzz_log_ros1, fuzz_log_rosbag2) and
// test_fuzz_regressions: a log file through every reading entry point.
#pragma once
#include <string>

#include "curvestereo/log.hpp"
#include "fuzz_util.hpp"

namespace cs::fuzz {

// "loaded", or the cs::Error's message; traps on a broken promise (a message of several
// lines, frames out of order, images of different sizes).
inline std::string readLog(const std::string& path) {
  std::string result = "loaded";
  try {
    const LogInfo info = logInfo(path);
    for (const LogTopic& t : info.topics)
      if (t.messages && t.firstNs > t.lastNs) __builtin_trap();
  } catch (const Error& e) {
    result = e.what();
  }
  try {
    const Sequence s = Sequence::openLog(path, "/cam0/image_raw", "/cam1/image_raw");
    ImageF l, r;
    for (size_t i = 0; i < s.frames().size(); ++i) {
      if (i && s.frames()[i].timestampNs < s.frames()[i - 1].timestampNs) __builtin_trap();
      s.load(i, l, r);
      if (l.width != r.width || l.height != r.height || l.empty()) __builtin_trap();
    }
  } catch (const Error& e) {
    if (result == "loaded") result = e.what();
  }
  if (result.find('\n') != std::string::npos) __builtin_trap();
  return result;
}

}  // namespace cs::fuzz
