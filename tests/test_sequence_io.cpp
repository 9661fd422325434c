// Tests for sequence.hpp: ASL/EuRoC folders, folder and glob pairs, poses files.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "curvestereo/image_io.hpp"
#include "curvestereo/sequence.hpp"
#include "test_util.hpp"

namespace {

namespace fs = std::filesystem;

// A temp folder removed when the test ends, pass or fail.
struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& name) : path(cs::test::tempDir("sequence_" + name)) {}
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

void writeText(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << text;
}

void writeImage(const fs::path& p, float value = 0.5f) {
  fs::create_directories(p.parent_path());
  cs::writePngGray(p.string(), cs::ImageF(4, 3, value));
}

// mav0/camN/data.csv (EuRoC's header, CRLF, spaces after commas, a blank line) and the images.
void writeAslCamera(const fs::path& mav0, const char* cam, const std::vector<int64_t>& stamps) {
  std::string csv = "#timestamp [ns],filename\r\n";
  for (int64_t t : stamps) {
    csv += std::to_string(t) + ", " + std::to_string(t) + ".png\r\n\r\n";
    writeImage(mav0 / cam / "data" / (std::to_string(t) + ".png"));
  }
  writeText(mav0 / cam / "data.csv", csv);
}

constexpr int64_t kT0 = 1000000000000, kStep = 33333333;

}  // namespace

TEST_CASE("ASL folder: frames paired by nearest timestamp; an unpaired frame is a warning naming it") {
  TempDir dir("asl");
  const fs::path mav0 = dir.path / "mav0";
  // cam1 lacks frame 2 and logs frame 1 0.4 ms late.
  writeAslCamera(mav0, "cam0", {kT0, kT0 + kStep, kT0 + 2 * kStep, kT0 + 3 * kStep});
  writeAslCamera(mav0, "cam1", {kT0, kT0 + kStep + 400000, kT0 + 3 * kStep});

  for (const fs::path& source : {dir.path, mav0}) {  // the folder holding mav0/, or mav0/ itself
    const cs::Sequence seq = cs::Sequence::open(source.string());
    REQUIRE(seq.frames().size() == 3);
    CHECK(seq.frames()[1].timestampNs == kT0 + kStep);
    CHECK(seq.frames()[1].rightPath == (mav0 / "cam1" / "data" / (std::to_string(kT0 + kStep + 400000) + ".png")));
    CHECK(seq.frames()[2].leftPath == (mav0 / "cam0" / "data" / (std::to_string(kT0 + 3 * kStep) + ".png")));
    CHECK(!seq.frames()[0].hasPose);
    REQUIRE(seq.warnings().size() == 1);
    CHECK(seq.warnings()[0] == "cam0 " + std::to_string(kT0 + 2 * kStep) + ".png: no cam1 frame within 1 ms");
    CHECK(seq.summary() == "3 stereo frames (ASL, no poses); 1 unpaired");
    cs::ImageF l, r;
    seq.load(2, l, r);
    CHECK(l.width == 4);
    CHECK(r.height == 3);
    CHECK(l(1, 1) == doctest::Approx(0.5).epsilon(0.01));
  }

  SUBCASE("a tighter tolerance leaves the late frame unpaired on both sides") {
    cs::SequenceOptions opt;
    opt.pairToleranceMs = 0.25;
    const cs::Sequence seq = cs::Sequence::open(dir.path.string(), opt);
    CHECK(seq.frames().size() == 2);
    CHECK(seq.summary() == "2 stereo frames (ASL, no poses); 3 unpaired");
    const std::string all = [&] {
      std::string s;
      for (const auto& w : seq.warnings()) s += w + "\n";
      return s;
    }();
    CHECK(all.find("cam0 " + std::to_string(kT0 + kStep) + ".png: no cam1 frame within 0.25 ms") != std::string::npos);
    CHECK(all.find("cam1 " + std::to_string(kT0 + kStep + 400000) + ".png: no cam0 frame within 0.25 ms") !=
          std::string::npos);
  }

  SUBCASE("a missing image: load names the frame and the file") {
    fs::remove(mav0 / "cam1" / "data" / (std::to_string(kT0) + ".png"));
    const cs::Sequence seq = cs::Sequence::open(dir.path.string());
    cs::ImageF l, r;
    CHECK_THROWS_WITH_AS(
        seq.load(0, l, r),
        doctest::Contains(("frame 0 (t " + std::to_string(kT0) + " ns), right image: cannot open image").c_str()),
        cs::Error);
    CHECK_THROWS_WITH_AS(seq.load(0, l, r), doctest::Contains((std::to_string(kT0) + ".png").c_str()), cs::Error);
    CHECK_THROWS_WITH_AS(seq.load(3, l, r), "sequence frame 3 does not exist (3 frames)", cs::Error);
  }

  SUBCASE("poses_cam0.csv next to mav0/ is attached; a frame without a pose is a warning") {
    writeText(dir.path / "poses_cam0.csv", "#timestamp [ns],px,py,pz,qx,qy,qz,qw\n" + std::to_string(kT0 + 2000000) +
                                               ",1,2,3,0,0,0,1\n" + std::to_string(kT0 + kStep) +
                                               ",1,2,3.035,0,0,0,1\n");
    const cs::Sequence seq = cs::Sequence::open(dir.path.string());
    CHECK(seq.frames()[0].hasPose);  // 2 ms off: within the default 5 ms
    CHECK(seq.frames()[1].hasPose);
    CHECK(!seq.frames()[2].hasPose);
    CHECK(seq.frames()[1].pose.t.z() == doctest::Approx(3.035));
    CHECK(seq.summary() == "3 stereo frames (ASL, 2 with poses); 1 unpaired");
    REQUIRE(seq.warnings().size() == 2);
    CHECK(seq.warnings()[1].find("1 of 3 frames have no pose within 5 ms") == 0);
    cs::SequenceOptions opt;
    opt.poseToleranceMs = 1.0;
    CHECK(!cs::Sequence::open(dir.path.string(), opt).frames()[0].hasPose);
  }

  SUBCASE("a malformed data.csv line is an error naming the file and line") {
    writeText(mav0 / "cam1" / "data.csv", "#timestamp [ns],filename\n\n1000,a.png\n12x4,b.png\n");
    CHECK_THROWS_WITH_AS(cs::Sequence::open(dir.path.string()),
                         doctest::Contains("cam1/data.csv line 4: timestamp '12x4' is not an integer (ns)"), cs::Error);
  }

  SUBCASE("no cam1: the error says what is missing") {
    fs::remove_all(mav0 / "cam1");
    CHECK_THROWS_WITH_AS(cs::Sequence::open(dir.path.string()), doctest::Contains("has no cam1/data.csv"), cs::Error);
  }
}

TEST_CASE("parseAslCsv: tolerant of layout, strict about content") {
  const auto rows = cs::parseAslCsv("\xEF\xBB\xBF#timestamp [ns],filename\r\n  20 ,  b.png \r\n\r\n10,a.png", "x.csv");
  REQUIRE(rows.size() == 2);  // sorted by timestamp
  CHECK(rows[0].timestampNs == 10);
  CHECK(rows[0].filename == "a.png");
  CHECK(rows[0].line == 4);
  CHECK(rows[1].filename == "b.png");
  CHECK(cs::parseAslCsv("", "x.csv").empty());
  CHECK_THROWS_WITH_AS(cs::parseAslCsv("1,a.png\n2,b.png,extra\n", "x.csv"),
                       "x.csv line 2: expected \"timestamp_ns,filename\", found '2,b.png,extra'", cs::Error);
  CHECK_THROWS_WITH_AS(cs::parseAslCsv("1,a.png\n-2,b.png\n", "x.csv"), doctest::Contains("x.csv line 2: timestamp"),
                       cs::Error);
  CHECK_THROWS_WITH_AS(cs::parseAslCsv("1,a.png\n1,b.png\n", "x.csv"), "x.csv line 2: timestamp 1 repeats line 1",
                       cs::Error);
  CHECK_THROWS_WITH_AS(cs::parseAslCsv("1,\n", "x.csv"), "x.csv line 1: empty filename", cs::Error);
  CHECK_THROWS_AS(cs::parseAslCsv("99999999999999999999,a.png\n", "x.csv"), cs::Error);
}

TEST_CASE("readPoses: CSV (ns) and TUM (seconds) give the same poses; the quaternion becomes R") {
  TempDir dir("poses");
  // 90 degrees about z: x -> y, y -> -x. The second line's quaternion is not unit (normalised).
  const double s = std::sqrt(0.5);
  writeText(dir.path / "poses.csv", "# t_ns, px, py, pz, qx, qy, qz, qw\r\n1000000000000, 1, 2, 3, 0, 0, " +
                                        std::to_string(s) + ", " + std::to_string(s) +
                                        "\r\n1000033333333,4,5,6,0,0,2,2\r\n");
  writeText(dir.path / "poses.txt",
            "# TUM: timestamp tx ty tz qx qy qz qw\n1000.000000000 1 2 3 0 0 0.7071068 0.7071068\n"
            "\t1000.033333333  4 5 6 0 0 2 2\n\n");
  for (const char* file : {"poses.csv", "poses.txt"}) {
    CAPTURE(file);
    const auto poses = cs::readPoses((dir.path / file).string());
    REQUIRE(poses.size() == 2);
    REQUIRE(poses.count(1000000000000) == 1);
    REQUIRE(poses.count(1000033333333) == 1);  // exactly, from seconds with 9 decimals
    for (const auto& [t, pose] : poses) {
      Eigen::Matrix3d expected;
      expected << 0, -1, 0, 1, 0, 0, 0, 0, 1;
      CHECK((pose.R - expected).norm() < 1e-6);
      CHECK((pose.R * Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitY()).norm() < 1e-6);
    }
    CHECK(poses.at(1000000000000).t == Eigen::Vector3d(1, 2, 3));
  }
  // A general rotation: 30 degrees about (1, 2, 2)/3, written as qx qy qz qw.
  const Eigen::AngleAxisd aa(std::acos(-1.0) / 6, Eigen::Vector3d(1, 2, 2) / 3);
  const Eigen::Quaterniond q(aa);
  char line[200];
  std::snprintf(line, sizeof line, "5.5 0 0 0 %.17g %.17g %.17g %.17g\n", q.x(), q.y(), q.z(), q.w());
  const auto poses = cs::parsePoses(line, "tum.txt");
  REQUIRE(poses.count(5500000000) == 1);
  CHECK((poses.at(5500000000).R - aa.toRotationMatrix()).norm() < 1e-12);
}

TEST_CASE("readPoses: malformed lines are one-line errors naming the file and line") {
  CHECK_THROWS_WITH_AS(cs::parsePoses("#h\n1,0,0,0,0,0,0,1\n2,0,0,nan,0,0,0,1\n", "p.csv"),
                       "p.csv line 3: value 4 'nan' is not a finite number", cs::Error);
  CHECK_THROWS_WITH_AS(cs::parsePoses("1,0,0,0,0,0,0,0\n", "p.csv"),
                       "p.csv line 1: the quaternion (qx, qy, qz, qw) is zero", cs::Error);
  CHECK_THROWS_WITH_AS(cs::parsePoses("1,0,0,0,0,0,1\n", "p.csv"),
                       doctest::Contains("p.csv line 1: expected 8 comma-separated values"), cs::Error);
  CHECK_THROWS_WITH_AS(cs::parsePoses("1.5,0,0,0,0,0,0,1\n", "p.csv"),
                       "p.csv line 1: timestamp '1.5' is not an integer (ns)", cs::Error);
  CHECK_THROWS_WITH_AS(cs::parsePoses("1 0 0 0 0 0 0 1\n1.0 0 0 0 0 0 0 1\n", "p.txt"),
                       "p.txt line 2: timestamp '1.0' repeats line 1", cs::Error);
  CHECK_THROWS_WITH_AS(cs::parsePoses("inf 0 0 0 0 0 0 1\n", "p.txt"),
                       "p.txt line 1: timestamp 'inf' is not a time in seconds", cs::Error);
  CHECK_THROWS_WITH_AS(cs::parsePoses("#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w []\n"
                                      "1,0,0,0,1,0,0,0,0,0,0,0,0,0,0,0,0\n",
                                      "gt.csv"),
                       doctest::Contains("EuRoC's ground truth is the IMU's pose"), cs::Error);
  CHECK_THROWS_WITH_AS(cs::readPoses("/nonexistent/poses.csv"), doctest::Contains("/nonexistent/poses.csv"), cs::Error);
  CHECK(cs::parsePoses("# only comments\n\n", "p.csv").empty());
}

TEST_CASE("LEFT,RIGHT: folders or globs paired by sorted (natural) name") {
  TempDir dir("pairs");
  for (int i : {8, 9, 10, 11}) {
    writeImage(dir.path / "left" / (std::to_string(kT0 + i * kStep) + ".png"), 0.1f * float(i % 3));
    writeImage(dir.path / "right" / (std::to_string(kT0 + i * kStep) + ".png"));
  }
  writeText(dir.path / "left" / "notes.txt", "not an image");
  const std::string left = (dir.path / "left").string(), right = (dir.path / "right").string();

  for (const std::string& source : {left + "," + right, left + "/*.png," + right + "/*.png"}) {
    CAPTURE(source);
    const cs::Sequence seq = cs::Sequence::open(source);
    REQUIRE(seq.frames().size() == 4);
    CHECK(seq.frames()[0].timestampNs == kT0 + 8 * kStep);
    CHECK(seq.frames()[3].timestampNs == kT0 + 11 * kStep);
    CHECK(seq.warnings().empty());
    CHECK(seq.summary() == "4 stereo frames (folder pairs, no poses); 0 unpaired");
  }

  SUBCASE("names that are not timestamps: natural order, 30 fps times, notes") {
    TempDir other("pairs_named");
    for (int i : {9, 10, 2}) {
      writeImage(other.path / "l" / ("img" + std::to_string(i) + ".png"));
      writeImage(other.path / "r" / ("cam1_" + std::to_string(i) + ".png"));
    }
    const cs::Sequence seq = cs::Sequence::open((other.path / "l").string() + "," + (other.path / "r").string());
    REQUIRE(seq.frames().size() == 3);
    CHECK(fs::path(seq.frames()[1].leftPath).filename() == "img9.png");
    CHECK(fs::path(seq.frames()[2].rightPath).filename() == "cam1_10.png");
    CHECK(seq.frames()[2].timestampNs == 66666667);
    REQUIRE(seq.warnings().size() == 2);
    CHECK(seq.warnings()[0].find("not integer timestamps") != std::string::npos);
    CHECK(seq.warnings()[1].find("paired by sorted name although the names differ") != std::string::npos);
  }

  SUBCASE("a count mismatch, an empty match, a missing folder are errors") {
    fs::remove(dir.path / "right" / (std::to_string(kT0 + 9 * kStep) + ".png"));
    CHECK_THROWS_WITH_AS(
        cs::Sequence::open(left + "," + right),
        ("'" + left + "' has 4 images but '" + right + "' has 3: folder pairs must have the same count").c_str(),
        cs::Error);
    CHECK_THROWS_WITH_AS(cs::Sequence::open(left + "/*.jpg," + right), doctest::Contains("matches no image files"),
                         cs::Error);
    CHECK_THROWS_WITH_AS(cs::Sequence::open(left + "," + right + "_x"), doctest::Contains("does not exist"), cs::Error);
  }
}

TEST_CASE("Sequence::open: an unknown source is a one-line error") {
  TempDir dir("unknown");
  CHECK_THROWS_WITH_AS(cs::Sequence::open((dir.path / "nope").string()), doctest::Contains("does not exist"),
                       cs::Error);
  CHECK_THROWS_WITH_AS(cs::Sequence::open(dir.path.string()), doctest::Contains("is not an ASL/EuRoC folder"),
                       cs::Error);
  writeText(dir.path / "file.txt", "x");
  CHECK_THROWS_WITH_AS(cs::Sequence::open((dir.path / "file.txt").string()), doctest::Contains("is a file"), cs::Error);
  writeAslCamera(dir.path / "mav0", "cam0", {kT0});
  writeAslCamera(dir.path / "mav0", "cam1", {kT0 + 5000000});
  CHECK_THROWS_WITH_AS(cs::Sequence::open(dir.path.string()), doctest::Contains("no stereo frames"), cs::Error);
  cs::SequenceOptions opt;
  opt.pairToleranceMs = -1;
  CHECK_THROWS_AS(cs::Sequence::open(dir.path.string(), opt), cs::Error);
}

TEST_CASE("shared data seqD1_indoor_walk: 16 posed frames, 3.5 cm per frame") {
  const std::string path = cs::test::sharedData("sequences/seqD1_indoor_walk");
  if (path.empty()) {
    MESSAGE("skipped: ../shared/data/sequences/seqD1_indoor_walk is not present");
    return;
  }
  const cs::Sequence seq = cs::Sequence::open(path);
  CHECK(seq.summary() == "16 stereo frames (ASL, 16 with poses); 0 unpaired");
  CHECK(seq.warnings().empty());
  REQUIRE(seq.frames().size() == 16);
  for (const auto& f : seq.frames()) CHECK(f.hasPose);
  const cs::Motion m = cs::motionBetween(seq.frames()[0].pose, seq.frames()[1].pose);
  MESSAGE("frame 0 -> 1: camera 0 moves " << m.t.norm() * 100 << " cm");
  CHECK(m.t.norm() == doctest::Approx(0.035).epsilon(0.05));
  CHECK((m.R - Eigen::Matrix3d::Identity()).norm() < 0.05);
  cs::ImageF l, r;
  seq.load(15, l, r);
  CHECK(l.width == 800);
  CHECK(r.height == 800);
}
