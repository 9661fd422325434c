// Stereo sequences: ASL/EuRoC folders, folder/glob pairs, poses files (sequence.hpp).
#include "curvestereo/sequence.hpp"

#include <glob.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>

#include "calib_common.hpp"
#include "curvestereo/image_io.hpp"
#include "sequence_pairing.hpp"

namespace cs {
namespace {

namespace fs = std::filesystem;
using calib::oneLine;

std::string trim(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t\r\v\f");
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t\r\v\f") - b + 1);
}

// A token quoted into a message: bounded, since fuzzed or binary input can be anything.
std::string shown(const std::string& token) {
  return "'" + (token.size() > 40 ? token.substr(0, 40) + "..." : token) + "'";
}

// Lines with CR/LF endings and a leading UTF-8 byte-order mark removed.
std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  size_t start = text.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0;
  while (start <= text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    out.push_back(text.substr(start, end - start));
    if (!out.back().empty() && out.back().back() == '\r') out.back().pop_back();
    start = end + 1;
  }
  return out;
}

std::vector<std::string> split(const std::string& line, bool commas) {
  std::vector<std::string> out;
  if (commas) {
    size_t start = 0;
    for (size_t comma; (comma = line.find(',', start)) != std::string::npos; start = comma + 1)
      out.push_back(trim(line.substr(start, comma - start)));
    out.push_back(trim(line.substr(start)));
  } else {
    size_t i = 0;
    while (true) {
      i = line.find_first_not_of(" \t\r\v\f", i);
      if (i == std::string::npos) break;
      const size_t e = std::min(line.find_first_of(" \t\r\v\f", i), line.size());
      out.push_back(line.substr(i, e - i));
      i = e;
    }
  }
  return out;
}

// Digits only, no sign, no overflow.
bool parseNs(const std::string& s, int64_t& out) {
  if (s.empty() || s.size() > 19) return false;
  uint64_t v = 0;
  for (char c : s) {
    if (c < '0' || c > '9') return false;
    v = v * 10 + uint64_t(c - '0');
  }
  if (v > uint64_t(std::numeric_limits<int64_t>::max())) return false;
  out = int64_t(v);
  return true;
}

// Seconds as TUM writes them ("1403636579.763555584") to ns: exact for plain decimals (a
// double holds epoch seconds only to ~0.2 us), through strtod for anything else.
bool parseSecondsNs(const std::string& s, int64_t& out) {
  const size_t dot = s.find('.');
  const std::string whole = s.substr(0, dot), frac = dot == std::string::npos ? "" : s.substr(dot + 1);
  int64_t sec = 0, fracNs = 0;
  if (parseNs(whole, sec) && (frac.empty() || parseNs(frac.substr(0, 9), fracNs)) &&
      frac.find_first_not_of("0123456789") == std::string::npos && sec <= 9'000'000'000) {
    for (size_t n = std::min<size_t>(frac.size(), 9); n < 9; ++n) fracNs *= 10;
    out = sec * 1'000'000'000 + fracNs;
    return true;
  }
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size() || !std::isfinite(v) || v < 0 || v > 9e9) return false;
  out = std::llround(v * 1e9);
  return true;
}

bool parseDouble(const std::string& s, double& out) {
  char* end = nullptr;
  out = std::strtod(s.c_str(), &end);
  return !s.empty() && end == s.c_str() + s.size() && std::isfinite(out);
}

[[noreturn]] void lineError(const std::string& name, size_t line, const std::string& problem) {
  throw Error(oneLine(name + " line " + std::to_string(line) + ": " + problem));
}

using detail::msText;

// Natural order ("img9" < "img10"), so that frame numbers without leading zeros pair right.
bool naturalLess(const std::string& a, const std::string& b) {
  const auto digit = [](char c) { return c >= '0' && c <= '9'; };
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (digit(a[i]) && digit(b[j])) {
      size_t ie = i, je = j;
      while (ie < a.size() && digit(a[ie])) ++ie;
      while (je < b.size() && digit(b[je])) ++je;
      while (i + 1 < ie && a[i] == '0') ++i;
      while (j + 1 < je && b[j] == '0') ++j;
      if (ie - i != je - j) return ie - i < je - j;
      if (const int c = a.compare(i, ie - i, b, j, je - j)) return c < 0;
      i = ie, j = je;
    } else {
      if (a[i] != b[j]) return (unsigned char)a[i] < (unsigned char)b[j];
      ++i, ++j;
    }
  }
  if (a.size() - i != b.size() - j) return a.size() - i < b.size() - j;
  return a < b;
}

// The PNG files of a folder, or the files a glob pattern matches, in natural order.
std::vector<std::string> listImages(const std::string& spec) {
  std::vector<std::string> files;
  std::error_code ec;
  if (fs::is_directory(spec, ec)) {
    for (const auto& entry : fs::directory_iterator(spec, ec)) {
      std::string ext = entry.path().extension().string();
      std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
      if (ext == ".png" && entry.is_regular_file(ec)) files.push_back(entry.path().string());
    }
    if (ec) throw Error(oneLine("cannot list folder '" + spec + "': " + ec.message()));
    if (files.empty()) throw Error(oneLine("folder '" + spec + "' holds no .png images"));
  } else if (spec.find_first_of("*?[") != std::string::npos) {
    glob_t g{};
    const int rc = ::glob(spec.c_str(), 0, nullptr, &g);
    for (size_t k = 0; rc == 0 && k < g.gl_pathc; ++k)
      if (fs::is_regular_file(g.gl_pathv[k], ec)) files.push_back(g.gl_pathv[k]);
    globfree(&g);
    if (files.empty()) throw Error(oneLine("pattern '" + spec + "' matches no image files"));
  } else {
    throw Error(oneLine("folder '" + spec + "' does not exist (in a \"LEFT,RIGHT\" sequence source)"));
  }
  std::sort(files.begin(), files.end(), naturalLess);
  return files;
}

}  // namespace

namespace detail {

void checkTolerances(const SequenceOptions& options) {
  if (!(options.pairToleranceMs >= 0) || !(options.poseToleranceMs >= 0) || !std::isfinite(options.pairToleranceMs) ||
      !std::isfinite(options.poseToleranceMs))
    throw Error("sequence tolerances must be finite and >= 0 ms");
}

fs::path aslMav0(const std::string& source) {
  std::error_code ec;
  for (const fs::path& mav0 : {fs::path(source) / "mav0", fs::path(source)})
    if (fs::is_directory(mav0 / "cam0", ec)) return mav0;
  return {};
}

std::string aslPoses(const std::string& source, const fs::path& mav0) {
  std::error_code ec;
  for (const fs::path& p : {fs::path(source) / "poses_cam0.csv", mav0 / "poses_cam0.csv"})
    if (fs::is_regular_file(p, ec)) return p.string();
  return "";
}

std::vector<AslRow> readAslCamera(const fs::path& mav0, const std::string& cam) {
  const fs::path csv = mav0 / cam / "data.csv";
  std::error_code ec;
  if (!fs::is_regular_file(csv, ec))
    throw Error(oneLine("ASL folder '" + mav0.string() + "' has no " + cam + "/data.csv"));
  return parseAslCsv(calib::readTextFile(csv.string()), csv.string());
}

std::vector<int64_t> timesOf(const std::vector<AslRow>& rows) {
  std::vector<int64_t> ns;
  for (const AslRow& r : rows) ns.push_back(r.timestampNs);
  return ns;
}

std::string msText(double ms) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g ms", ms);
  return buf;
}

TimePairs pairByTime(const std::vector<int64_t>& left, const std::vector<int64_t>& right, double toleranceMs) {
  const auto nearest = [](const std::vector<int64_t>& ts, int64_t t) -> size_t {
    auto it = std::lower_bound(ts.begin(), ts.end(), t);
    if (it == ts.end()) return ts.size() - 1;
    if (it != ts.begin() && t - *std::prev(it) <= *it - t) --it;
    return size_t(it - ts.begin());
  };
  const double tolNs = toleranceMs * 1e6;
  TimePairs out;
  std::vector<bool> rightUsed(right.size(), false);
  for (size_t i = 0; i < left.size(); ++i) {
    const size_t j = right.empty() ? 0 : nearest(right, left[i]);
    if (right.empty() || nearest(left, right[j]) != i || std::fabs(double(right[j]) - double(left[i])) > tolNs) {
      out.leftAlone.push_back(i);
      continue;
    }
    rightUsed[j] = true;
    out.pairs.emplace_back(i, j);
  }
  for (size_t j = 0; j < right.size(); ++j)
    if (!rightUsed[j]) out.rightAlone.push_back(j);
  return out;
}

}  // namespace detail

std::vector<AslRow> parseAslCsv(const std::string& text, const std::string& name) {
  std::vector<AslRow> rows;
  const std::vector<std::string> all = lines(text);
  for (size_t n = 0; n < all.size(); ++n) {
    const std::string line = trim(all[n]);
    if (line.empty() || line[0] == '#') continue;
    const std::vector<std::string> f = split(line, true);
    if (f.size() != 2) lineError(name, n + 1, "expected \"timestamp_ns,filename\", found " + shown(line));
    AslRow row{0, f[1], int(n + 1)};
    if (!parseNs(f[0], row.timestampNs)) lineError(name, n + 1, "timestamp " + shown(f[0]) + " is not an integer (ns)");
    if (row.filename.empty()) lineError(name, n + 1, "empty filename");
    rows.push_back(std::move(row));
  }
  std::stable_sort(rows.begin(), rows.end(),
                   [](const AslRow& a, const AslRow& b) { return a.timestampNs < b.timestampNs; });
  for (size_t k = 1; k < rows.size(); ++k)
    if (rows[k].timestampNs == rows[k - 1].timestampNs)
      lineError(name, size_t(std::max(rows[k].line, rows[k - 1].line)),
                "timestamp " + std::to_string(rows[k].timestampNs) + " repeats line " +
                    std::to_string(std::min(rows[k].line, rows[k - 1].line)));
  return rows;
}

std::map<int64_t, Pose> parsePoses(const std::string& text, const std::string& name) {
  std::map<int64_t, Pose> poses;
  std::map<int64_t, size_t> lineOf;
  int csv = -1;  // decided by the first data line: a comma means CSV (t_ns), else TUM (t_s)
  bool euroc = false;
  const std::vector<std::string> all = lines(text);
  for (size_t n = 0; n < all.size(); ++n) {
    const std::string line = trim(all[n]);
    if (line.empty()) continue;
    if (line[0] == '#') {
      euroc = euroc || line.find("q_RS_w") != std::string::npos;
      continue;
    }
    if (csv < 0) csv = line.find(',') != std::string::npos;
    const std::vector<std::string> f = split(line, csv);
    if (f.size() != 8)
      lineError(
          name, n + 1,
          std::string(csv ? "expected 8 comma-separated values \"t_ns,px,py,pz,qx,qy,qz,qw\", found "
                          : "expected 8 space-separated values \"t_seconds tx ty tz qx qy qz qw\", found ") +
              std::to_string(f.size()) +
              (euroc ? " (EuRoC's ground truth is the IMU's pose with qw first: convert it to T_world_cam0)" : ""));
    int64_t t = 0;
    if (csv ? !parseNs(f[0], t) : !parseSecondsNs(f[0], t))
      lineError(name, n + 1,
                "timestamp " + shown(f[0]) + (csv ? " is not an integer (ns)" : " is not a time in seconds"));
    double v[7];
    for (int k = 0; k < 7; ++k)
      if (!parseDouble(f[k + 1], v[k]))
        lineError(name, n + 1, "value " + std::to_string(k + 2) + " " + shown(f[k + 1]) + " is not a finite number");
    // Scaled by its largest component first, so that huge values cannot overflow the norm.
    const double m = std::max({std::fabs(v[3]), std::fabs(v[4]), std::fabs(v[5]), std::fabs(v[6])});
    if (m < 1e-6) lineError(name, n + 1, "the quaternion (qx, qy, qz, qw) is zero");
    if (const auto it = lineOf.find(t); it != lineOf.end())
      lineError(name, n + 1, "timestamp " + shown(f[0]) + " repeats line " + std::to_string(it->second));
    lineOf[t] = n + 1;
    poses[t] = Pose::fromQuaternion(Eigen::Vector3d(v[0], v[1], v[2]), v[3] / m, v[4] / m, v[5] / m, v[6] / m);
  }
  return poses;
}

std::map<int64_t, Pose> readPoses(const std::string& path) { return parsePoses(calib::readTextFile(path), path); }

Sequence Sequence::open(const std::string& source, const SequenceOptions& options) {
  detail::checkTolerances(options);
  Sequence seq;
  std::string posesPath = options.poses;
  std::error_code ec;
  if (fs::is_directory(source, ec)) {
    // (a) ASL/EuRoC: the folder holding mav0/, or mav0/ itself.
    const fs::path mav0 = detail::aslMav0(source);
    if (mav0.empty())
      throw Error(oneLine("'" + source + "' is not an ASL/EuRoC folder (no mav0/cam0/ or cam0/ in it); for two image " +
                          "folders give \"LEFT,RIGHT\""));
    if (posesPath.empty()) posesPath = detail::aslPoses(source, mav0);
    seq.kind_ = "ASL";
    const std::vector<AslRow> left = detail::readAslCamera(mav0, "cam0"), right = detail::readAslCamera(mav0, "cam1");
    const detail::TimePairs paired =
        detail::pairByTime(detail::timesOf(left), detail::timesOf(right), options.pairToleranceMs);
    for (const auto& [i, j] : paired.pairs) {
      SequenceFrame f;
      f.timestampNs = left[i].timestampNs;
      f.leftPath = (mav0 / "cam0" / "data" / left[i].filename).string();
      f.rightPath = (mav0 / "cam1" / "data" / right[j].filename).string();
      seq.frames_.push_back(std::move(f));
    }
    for (size_t i : paired.leftAlone)
      seq.warnings_.push_back("cam0 " + left[i].filename + ": no cam1 frame within " + msText(options.pairToleranceMs));
    for (size_t j : paired.rightAlone)
      seq.warnings_.push_back("cam1 " + right[j].filename + ": no cam0 frame within " +
                              msText(options.pairToleranceMs));
    seq.unpaired_ += paired.leftAlone.size() + paired.rightAlone.size();
    if (seq.frames_.empty())
      throw Error(oneLine("ASL folder '" + mav0.string() + "': no stereo frames (cam0 has " +
                          std::to_string(left.size()) + ", cam1 " + std::to_string(right.size()) +
                          ", none paired within " + msText(options.pairToleranceMs) + ")"));
  } else if (source.find(',') != std::string::npos) {
    // (b) "LEFT,RIGHT" folders or globs, paired by sorted name.
    const size_t comma = source.find(',');
    const std::string leftSpec = source.substr(0, comma), rightSpec = source.substr(comma + 1);
    const std::vector<std::string> left = listImages(leftSpec), right = listImages(rightSpec);
    if (left.size() != right.size())
      throw Error(oneLine("'" + leftSpec + "' has " + std::to_string(left.size()) + " images but '" + rightSpec +
                          "' has " + std::to_string(right.size()) + ": folder pairs must have the same count"));
    seq.kind_ = "folder pairs";
    std::vector<int64_t> stemNs(left.size()), rightNs(right.size());
    bool leftTimed = true, rightTimed = true;
    size_t firstDiffering = left.size(), farApart = 0, firstFar = 0;
    for (size_t i = 0; i < left.size(); ++i) {
      leftTimed = leftTimed && parseNs(fs::path(left[i]).stem().string(), stemNs[i]);
      rightTimed = rightTimed && parseNs(fs::path(right[i]).stem().string(), rightNs[i]);
      if (firstDiffering == left.size() && fs::path(left[i]).filename() != fs::path(right[i]).filename())
        firstDiffering = i;
    }
    for (size_t i = 0; i < left.size(); ++i) {
      SequenceFrame f;
      f.timestampNs = leftTimed ? stemNs[i] : int64_t(std::llround(double(i) * 1e9 / 30.0));
      f.leftPath = left[i];
      f.rightPath = right[i];
      seq.frames_.push_back(std::move(f));
      if (leftTimed && rightTimed && std::fabs(double(stemNs[i]) - double(rightNs[i])) > options.pairToleranceMs * 1e6)
        if (farApart++ == 0) firstFar = i;
    }
    if (!leftTimed)
      seq.warnings_.push_back("left file names are not integer timestamps (ns): frame i is given time i/30 s");
    if (firstDiffering < left.size())
      seq.warnings_.push_back("left and right images are paired by sorted name although the names differ (first: '" +
                              left[firstDiffering] + "' with '" + right[firstDiffering] + "')");
    if (farApart)
      seq.warnings_.push_back(std::to_string(farApart) + " pairs' file-name timestamps differ by more than " +
                              msText(options.pairToleranceMs) + " (first: '" + left[firstFar] + "' with '" +
                              right[firstFar] + "')");
  } else if (fs::exists(source, ec)) {
    throw Error(oneLine("sequence source '" + source + "' is a file; expected an ASL/EuRoC folder or \"LEFT,RIGHT\""));
  } else {
    throw Error(oneLine("sequence source '" + source + "' does not exist (expected an ASL/EuRoC folder or " +
                        "\"LEFT,RIGHT\" image folders or glob patterns)"));
  }

  if (!posesPath.empty()) seq.attachPoses(posesPath, options.poseToleranceMs);
  return seq;
}

namespace detail {

const Pose* nearestPose(const std::map<int64_t, Pose>& poses, int64_t t, double toleranceMs) {
  auto it = poses.lower_bound(t);
  if (it != poses.begin() && (it == poses.end() || t - std::prev(it)->first < it->first - t)) --it;
  if (it == poses.end() || double(std::max(it->first, t) - std::min(it->first, t)) > toleranceMs * 1e6) return nullptr;
  return &it->second;
}

std::string missingPosesText(const std::vector<int64_t>& missing, size_t frames, double toleranceMs,
                             const std::string& path) {
  std::string list;
  for (size_t k = 0; k < missing.size() && k < 5; ++k) list += (k ? ", " : "") + std::to_string(missing[k]);
  return std::to_string(missing.size()) + " of " + std::to_string(frames) + " frames have no pose within " +
         msText(toleranceMs) + " in '" + path + "' (t_ns " + list + (missing.size() > 5 ? ", ..." : "") + ")";
}

}  // namespace detail

void Sequence::attachPoses(const std::string& path, double toleranceMs) {
  posesGiven_ = true;
  const std::map<int64_t, Pose> poses = readPoses(path);
  std::vector<int64_t> missing;
  for (SequenceFrame& f : frames_) {
    const Pose* pose = detail::nearestPose(poses, f.timestampNs, toleranceMs);
    if (pose) f.hasPose = true, f.pose = *pose;
    if (!pose) missing.push_back(f.timestampNs);
  }
  if (!missing.empty()) warnings_.push_back(detail::missingPosesText(missing, frames_.size(), toleranceMs, path));
}

std::string Sequence::summary() const {
  const size_t posed = size_t(std::count_if(frames_.begin(), frames_.end(), [](const auto& f) { return f.hasPose; }));
  return std::to_string(frames_.size()) + " stereo frames (" + kind_ + ", " +
         (posesGiven_ ? std::to_string(posed) + " with poses" : std::string("no poses")) + "); " +
         std::to_string(unpaired_) + " unpaired";
}

namespace {

std::string frameName(size_t i, const SequenceFrame& f) {
  return "frame " + std::to_string(i) + " (t " + std::to_string(f.timestampNs) + " ns)";
}

// readPngGray with the frame named in its errors.
ImageF readFrameImage(const std::string& frame, const std::string& path, const char* side, ImageU8* bytes) {
  try {
    return readPngGray(path, nullptr, bytes);
  } catch (const Error& e) {
    throw Error(oneLine(frame + ", " + side + " image: " + e.what()));  // e names the file
  }
}

template <class Img>
void requireSameSize(const std::string& frame, const SequenceFrame& f, const Img& l, const Img& r) {
  if (l.width != r.width || l.height != r.height)
    throw Error(oneLine(frame + ": left image '" + f.leftPath + "' is " + std::to_string(l.width) + "x" +
                        std::to_string(l.height) + " but right image '" + f.rightPath + "' is " +
                        std::to_string(r.width) + "x" + std::to_string(r.height)));
}

}  // namespace

const SequenceFrame& Sequence::frameAt(size_t i) const {
  if (i >= frames_.size())
    throw Error("sequence frame " + std::to_string(i) + " does not exist (" + std::to_string(frames_.size()) +
                " frames)");
  return frames_[i];
}

void Sequence::load(size_t i, ImageF& left, ImageF& right) const {
  const SequenceFrame& f = frameAt(i);
  if (log_) return loadLog(i, left, right);
  const std::string frame = frameName(i, f);
  ImageF l = readFrameImage(frame, f.leftPath, "left", nullptr),
         r = readFrameImage(frame, f.rightPath, "right", nullptr);
  requireSameSize(frame, f, l, r);
  left = std::move(l);
  right = std::move(r);
}

bool Sequence::loadBytes(size_t i, ImageU8& left, ImageU8& right) const {
  const SequenceFrame& f = frameAt(i);
  if (log_) return false;
  const std::string frame = frameName(i, f);
  ImageU8 l, r;
  if (!readFrameImage(frame, f.leftPath, "left", &l).empty()) return false;
  if (!readFrameImage(frame, f.rightPath, "right", &r).empty()) return false;
  requireSameSize(frame, f, l, r);
  left = std::move(l);
  right = std::move(r);
  return true;
}

}  // namespace cs
