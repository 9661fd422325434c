// Every input in tests/fuzz/regressions/<target>/ (crashes the libFuzzer targets found,
// kept after the fix) and every seed in tests/fuzz/corpus/<target>/ goes through the
// same reader as its fuzz target: it must load or throw a one-line cs::Error, never
// crash, hang or throw anything else. Run under ASan/UBSan in CI.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "curvestereo/camera_rig.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/rig.hpp"
#include "curvestereo/sequence.hpp"
#include "fuzz/fuzz_log.hpp"
#include "fuzz/fuzz_vins.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;

namespace {

fs::path fuzzDir() { return fs::path(cs::test::goldenDir()).parent_path() / "fuzz"; }

std::string readAll(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

// "loaded" or the error message.
std::string load(const std::string& target, const fs::path& file) {
  try {
    if (target == "camchain") {
      cs::parseKalibr(readAll(file), file.filename().string());
      cs::loadKalibr(file.string());
    } else if (target == "camera_rig") {
      cs::parseCameraRig(readAll(file), file.filename().string());
      cs::loadCameraRig(file.string());
    } else if (target == "calib") {
      cs::parseCalibration(readAll(file), file.filename().string());
      cs::loadCalibration(file.string());
    } else if (target == "basalt") {
      cs::parseBasalt(readAll(file), file.filename().string());
      cs::loadBasalt(file.string());
    } else if (target == "opencv") {
      cs::parseOpenCv(readAll(file), file.filename().string());
      cs::loadOpenCv(file.string());
    } else if (target == "orbslam3") {
      cs::parseOrbSlam3(readAll(file), file.filename().string());
      cs::loadOrbSlam3(file.string());
    } else if (target == "vins") {  // fuzz_vins.hpp's input: config, "###", camera file
      cs::fuzz::parseVinsInput(readAll(file));
    } else if (target == "png") {
      cs::readPngGray(file.string());
    } else if (target == "exr") {
      cs::readExr(file.string());
    } else if (target == "flo") {
      cs::readFlo(file.string());
    } else if (target == "sequence") {  // fuzz_sequence runs both readers; a seed is named for its format
      if (file.filename().string().rfind("poses", 0) == 0)
        cs::readPoses(file.string());
      else
        cs::parseAslCsv(readAll(file), file.filename().string());
    } else if (target.rfind("log_", 0) == 0) {  // log_mcap, log_ros1, log_rosbag2: fuzz_log.hpp
      const std::string result = cs::fuzz::readLog(file.string());
      if (result != "loaded") return result;
    } else {
      FAIL("unknown fuzz target directory " << target);
    }
  } catch (const cs::Error& e) {
    return e.what();
  }
  return "loaded";
}

// Returns how many files it replayed; with mustLoad (the seeds: all valid files) each must load.
int replay(const char* kind, bool mustLoad) {
  int files = 0;
  const fs::path root = fuzzDir() / kind;
  if (!fs::exists(root)) return 0;
  for (const auto& targetDir : fs::directory_iterator(root)) {
    if (!targetDir.is_directory()) continue;
    const std::string target = targetDir.path().filename().string();
    for (const auto& entry : fs::directory_iterator(targetDir.path())) {
      if (!entry.is_regular_file()) continue;
      CAPTURE(entry.path().string());
      const std::string result = load(target, entry.path());
      CHECK(result.find('\n') == std::string::npos);
      CHECK(!result.empty());
      if (mustLoad) CHECK(result == "loaded");
      if (!mustLoad) MESSAGE(target << "/" << entry.path().filename().string() << ": " << result);
      ++files;
    }
  }
  return files;
}

}  // namespace

TEST_CASE("fuzz regressions: every crash input found so far loads or is a cs::Error") {
  const int files = replay("regressions", false);
  MESSAGE(files << " regression inputs replayed");
}

TEST_CASE("fuzz seed corpus: every seed loads or is a cs::Error") {
  const int files = replay("corpus", true);
  CHECK(files > 40);
}

TEST_CASE("every calibration seed is read the same by parseCalibration (format detected) and its own reader") {
  for (const char* target : {"camchain", "basalt", "opencv", "orbslam3"})
    for (const auto& entry : fs::directory_iterator(fuzzDir() / "corpus" / target)) {
      CAPTURE(entry.path().string());
      const std::string text = readAll(entry.path());
      const std::string t = target;
      const cs::Rig own = t == "camchain" ? cs::parseKalibr(text)
                          : t == "basalt" ? cs::parseBasalt(text)
                          : t == "opencv" ? cs::parseOpenCv(text)
                                          : cs::parseOrbSlam3(text);
      const cs::Rig detected = cs::parseCalibration(text);
      CHECK(detected.cam0.params == own.cam0.params);
      CHECK(detected.cam1.params == own.cam1.params);
      CHECK(detected.R == own.R);
      CHECK(detected.t == own.t);
    }
}

TEST_CASE("parseKalibr (the fuzzed entry) reads text exactly as loadKalibr reads the file") {
  for (const auto& entry : fs::directory_iterator(fuzzDir() / "corpus" / "camchain")) {
    CAPTURE(entry.path().string());
    const cs::Rig fromFile = cs::loadKalibr(entry.path().string());
    const cs::Rig fromText = cs::parseKalibr(readAll(entry.path()));
    CHECK(fromText.cam0.params == fromFile.cam0.params);
    CHECK(fromText.cam1.params == fromFile.cam1.params);
    CHECK(fromText.cam1.width == fromFile.cam1.width);
    CHECK(fromText.R == fromFile.R);
    CHECK(fromText.t == fromFile.t);
  }
  CHECK_THROWS_WITH_AS(cs::parseKalibr("cam0: [", "inline.yaml"), doctest::Contains("inline.yaml: YAML syntax error"),
                       cs::Error);
}
