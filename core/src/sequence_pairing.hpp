// What ASL folders, rig folders and logs share (sequence_io.cpp): pairing cameras' frames by
// timestamp, attaching poses, and reading an ASL folder's cameras.
#pragma once
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "curvestereo/pose.hpp"
#include "curvestereo/sequence.hpp"

namespace cs::detail {

struct TimePairs {
  std::vector<std::pair<size_t, size_t>> pairs;  // (left, right) indexes, in left order
  std::vector<size_t> leftAlone, rightAlone;     // frames without a partner
};

// Mutual nearest neighbours within toleranceMs: one-to-one, and a frame missing from one
// camera cannot pull its neighbour's partner away. Both lists sorted ascending.
TimePairs pairByTime(const std::vector<int64_t>& left, const std::vector<int64_t>& right, double toleranceMs);

std::string msText(double ms);  // "1 ms"

// Throws "sequence tolerances must be finite and >= 0 ms" unless both are.
void checkTolerances(const SequenceOptions& options);

// An ASL folder's mav0/ (the folder holding cam0/: source/mav0 or source itself), or an
// empty path when source has neither.
std::filesystem::path aslMav0(const std::string& source);
// The poses file an ASL folder brings: poses_cam0.csv beside mav0/ or in it; "" when none.
std::string aslPoses(const std::string& source, const std::filesystem::path& mav0);
// mav0/<cam>/data.csv, parsed (parseAslCsv); a one-line cs::Error when it is missing.
std::vector<AslRow> readAslCamera(const std::filesystem::path& mav0, const std::string& cam);
std::vector<int64_t> timesOf(const std::vector<AslRow>& rows);

// The pose nearest to t (the first at or after it, or the one before) when it lies within
// toleranceMs: no interpolation, since a pose from another instant is wrong for a moving rig.
const Pose* nearestPose(const std::map<int64_t, Pose>& poses, int64_t t, double toleranceMs);
// "3 of 16 frames have no pose within 5 ms in 'FILE' (t_ns 1, 2, 3)": the frames left
// without one, at most five named.
std::string missingPosesText(const std::vector<int64_t>& missing, size_t frames, double toleranceMs,
                             const std::string& path);

}  // namespace cs::detail
