// A rig's recorded sequence (issue 32, item 4): RigSequence reads ASL folders with one cam<k>
// per camera, pairs every camera to camera 0 by timestamp and names what it leaves out; `run
// --sequence` on such a folder solves every frame through RigStereo::next and writes each
// frame's cameras and panorama into OUT/<t_ns>/.
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cli_util.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/rig_sequence.hpp"
#include "synth/rig.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using cs::test::checkRefused;
using cs::test::errorOf;
using cs::test::runCli;

namespace {

void writeText(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path) << text;
}

// mav0/cam<k>/data.csv listing `times[k]` (ns), each image an 8x8 grey PNG.
void writeAsl(const fs::path& dir, const std::vector<std::vector<long long>>& times) {
  for (size_t k = 0; k < times.size(); ++k) {
    const fs::path cam = dir / "mav0" / ("cam" + std::to_string(k));
    std::string csv = "#timestamp [ns],filename\n";
    for (long long t : times[k]) {
      csv += std::to_string(t) + "," + std::to_string(t) + ".png\n";
      fs::create_directories(cam / "data");
      cs::writePngGray((cam / "data" / (std::to_string(t) + ".png")).string(), cs::ImageF(8, 8, 0.25f * float(k)));
    }
    writeText(cam / "data.csv", csv);
  }
}

// The first n cameras of ring6 (a rig for the reader: it reads the count and camera 0's pose).
cs::CameraRig ringOf(int n) {
  cs::CameraRig rig = cs::synth::rigLayout("ring6", 16).rig;
  rig.cameras.resize(size_t(n));
  rig.poses.resize(size_t(n));
  return rig;
}

}  // namespace

TEST_CASE("RigSequence pairs every camera to camera 0 and names each image it leaves out") {
  const fs::path dir = cs::test::tempDir("rig_sequence_pairing");
  constexpr long long t0 = 1'000'000'000, dt = 33'333'333;
  // cam1 is 0.2 ms late at frame 0; cam2 misses frame 2 and has one image of its own.
  writeAsl(dir, {{t0, t0 + dt, t0 + 2 * dt}, {t0 + 200'000, t0 + dt, t0 + 2 * dt}, {t0, t0 + dt, t0 + 5 * dt}});
  writeText(dir / "poses_cam0.csv", "# t_ns,px,py,pz,qx,qy,qz,qw\n" + std::to_string(t0) + ",1,2,3,0,0,0,1\n");
  const cs::CameraRig rig = ringOf(3);
  const cs::RigSequence seq = cs::RigSequence::open(dir.string(), rig);
  REQUIRE(seq.frames().size() == 2);
  CHECK(seq.cameras() == 3);
  CHECK(seq.frames()[0].timestampNs == t0);
  CHECK(seq.frames()[0].paths[1].find("cam1/data/1000200000.png") != std::string::npos);
  CHECK(seq.frames()[1].paths[2].find("cam2/data/1033333333.png") != std::string::npos);
  CHECK(seq.frames()[0].hasPose);
  // The rig's pose: camera 0's centre on the body lands where the file puts camera 0.
  const cs::Pose& body = seq.frames()[0].bodyPose;
  const Eigen::Vector3d cam0 = body.R * rig.poses[0].p + body.t;
  CHECK((cam0 - Eigen::Vector3d(1, 2, 3)).norm() < 1e-12);
  CHECK((body.R * rig.poses[0].R - Eigen::Matrix3d::Identity()).norm() < 1e-12);
  CHECK_FALSE(seq.frames()[1].hasPose);
  // cam0's and cam1's images of frame 2 and cam2's own one: three images in no frame.
  CHECK(seq.summary() == "2 frames of 3 cameras (ASL, 1 with poses); 3 images unpaired");
  const std::vector<std::string>& w = seq.warnings();
  REQUIRE(w.size() == 3);
  CHECK(w[0] == "cam2 1166666665.png: no cam0 frame within 1 ms");
  CHECK(w[1] == "cam0 1066666666.png: no cam2 frame within 1 ms");
  CHECK(w[2].rfind("1 of 2 frames have no pose within 5 ms", 0) == 0);
  std::vector<cs::ImageF> images;
  seq.load(1, images);
  REQUIRE(images.size() == 3);
  CHECK(images[2](3, 3) == doctest::Approx(0.5f).epsilon(0.01));

  // A wider tolerance is the user's to give; two cameras of the three make a rig too.
  cs::SequenceOptions loose;
  loose.pairToleranceMs = 0.1;
  CHECK(cs::RigSequence::open(dir.string(), rig, loose).frames().size() == 1);  // cam1's late frame 0 drops out
  CHECK(cs::RigSequence::open((dir / "mav0").string(), ringOf(2)).frames().size() == 3);
}

TEST_CASE("RigSequence::camerasIn counts the cam<k> folders of an ASL folder or its mav0") {
  const fs::path dir = cs::test::tempDir("rig_sequence_count");
  CHECK(cs::RigSequence::camerasIn(dir.string()) == 0);
  CHECK(cs::RigSequence::camerasIn((dir / "missing").string()) == 0);
  writeAsl(dir, {{1}, {1}, {1}});
  CHECK(cs::RigSequence::camerasIn(dir.string()) == 3);
  CHECK(cs::RigSequence::camerasIn((dir / "mav0").string()) == 3);
  fs::remove(dir / "mav0" / "cam1" / "data.csv");  // the count stops at the first gap
  CHECK(cs::RigSequence::camerasIn(dir.string()) == 1);
}

TEST_CASE("RigSequence refuses what it cannot read in one line naming the camera, file and frame") {
  const fs::path dir = cs::test::tempDir("rig_sequence_errors");
  constexpr long long t0 = 2'000'000'000;
  writeAsl(dir, {{t0, t0 + 1000}, {t0, t0 + 1000}});
  CHECK(errorOf([&] { cs::RigSequence::open(dir.string(), ringOf(3)); }).find("has no cam2/data.csv") !=
        std::string::npos);
  CHECK(errorOf([&] { cs::RigSequence::open(dir.string(), ringOf(1)); }) ==
        "a rig sequence needs at least two cameras, got 1");
  CHECK(errorOf([&] {
          cs::RigSequence::open((dir / "nope").string(), ringOf(2));
        }).find("is not an ASL/EuRoC folder") != std::string::npos);
  writeText(dir / "mav0/cam1/data.csv", "#timestamp [ns],filename\n5,a.png\nnot a row\n");
  CHECK(errorOf([&] { cs::RigSequence::open(dir.string(), ringOf(2)); }).find("cam1/data.csv line 3:") !=
        std::string::npos);
  writeText(dir / "mav0/cam1/data.csv", "#timestamp [ns],filename\n5,a.png\n");
  CHECK(errorOf([&] {
          cs::RigSequence::open(dir.string(), ringOf(2));
        }).find("no frame has an image of all 2 cameras") != std::string::npos);
  writeAsl(dir, {{t0, t0 + 1000}, {t0, t0 + 1000}});
  fs::remove(dir / "mav0/cam1/data" / (std::to_string(t0 + 1000) + ".png"));
  const cs::RigSequence seq = cs::RigSequence::open(dir.string(), ringOf(2));
  std::vector<cs::ImageF> images;
  seq.load(0, images);
  const std::string e = errorOf([&] { seq.load(1, images); });
  CHECK(e.rfind("frame 1 (t 2000001000 ns), cam1 image: ", 0) == 0);
  CHECK(e.find("2000001000.png") != std::string::npos);
}

TEST_CASE("run --sequence on a rig's folder: every frame's cameras and panorama, warm after the first") {
  cs::synth::RigConfig cfg;
  cfg.size = 64;
  cfg.samplesPerAxis = 1;
  cfg.panoramaWidth = 128;
  const cs::synth::SynthRig rendered = cs::synth::renderRig(cfg);
  const fs::path dir = cs::test::tempDir("cli_rig_sequence");
  cs::synth::writeRigFolder(rendered, cfg, (dir / "still").string());
  // A still rig filmed three times, with its (constant) pose.
  constexpr long long t0 = 5'000'000'000, dt = 33'333'333;
  std::vector<std::vector<long long>> times(4, {t0, t0 + dt, t0 + 2 * dt});
  writeAsl(dir / "seq", times);
  for (int k = 0; k < 4; ++k)
    for (long long t : times[size_t(k)])
      fs::copy_file(dir / "still" / ("cam" + std::to_string(k) + ".png"),
                    dir / "seq/mav0" / ("cam" + std::to_string(k)) / "data" / (std::to_string(t) + ".png"),
                    fs::copy_options::overwrite_existing);
  fs::copy_file(dir / "still/camchain.yaml", dir / "seq/camchain.yaml");
  std::string poses = "# t_ns,px,py,pz,qx,qy,qz,qw\n";
  for (long long t : times[0]) poses += std::to_string(t) + ",0,0,0,0,0,0,1\n";
  writeText(dir / "seq/poses_cam0.csv", poses);
  // Small images: three levels keep the band sweep's level wide enough for warm starts, on
  // the window of about 36 x 64 px each direction solves (the side its partner sees).
  const std::string solve = " --backend cpu --levels 3 --min-width 8 --panorama-width 128";

  const cs::test::CliOutcome o = runCli(dir, "run --sequence seq -o out" + solve);
  CAPTURE(o.out);
  CAPTURE(o.err);
  REQUIRE(o.exitCode == 0);
  CHECK(o.out.find("sequence: 3 frames of 4 cameras (ASL, 3 with poses); 0 images unpaired") != std::string::npos);
  CHECK(o.out.find("16 solves warm, 8 cold, 0 warm ones redone cold") != std::string::npos);
  for (long long t : times[0]) {
    const fs::path frame = dir / "out" / std::to_string(t);
    CHECK(fs::exists(frame / "panorama_range.exr"));
    CHECK(fs::exists(frame / "points.ply"));
    for (int k = 0; k < 4; ++k) CHECK(fs::exists(frame / ("cam" + std::to_string(k)) / "depth.exr"));
  }
  // The first frame is the cold solve of those images: a one-frame run, bit for bit.
  REQUIRE(runCli(dir,
                 "run --calib still/camchain.yaml still/cam0.png still/cam1.png still/cam2.png "
                 "still/cam3.png -o one" +
                     solve)
              .exitCode == 0);
  CHECK(cs::test::sameBits(cs::readExr((dir / "out" / std::to_string(t0) / "panorama_range.exr").string()),
                           cs::readExr((dir / "one/panorama_range.exr").string())));
  CHECK(cs::test::sameBits(cs::readExr((dir / "out" / std::to_string(t0) / "cam2/depth.exr").string()),
                           cs::readExr((dir / "one/cam2/depth.exr").string())));

  CHECK(runCli(dir, "run --sequence seq -o cold --cold" + solve).out.find("0 solves warm, 24 cold") !=
        std::string::npos);
  // A frame that cannot be read stops the run with one line; the frames before it stay.
  fs::remove(dir / "seq/mav0/cam3/data" / (std::to_string(t0 + 2 * dt) + ".png"));
  const cs::test::CliOutcome broken = runCli(dir, "run --sequence seq --calib seq/camchain.yaml -o broken" + solve);
  checkRefused(broken, "frame 2 (t 5066666666 ns), cam3 image:");
  CHECK(broken.err.find("(2 frames before it are written)") != std::string::npos);
  CHECK(fs::exists(dir / "broken" / std::to_string(t0 + dt) / "panorama_range.exr"));
  checkRefused(runCli(dir, "run --sequence seq --calib seq/camchain.yaml -o x --pinhole 90" + solve),
               "--pinhole is for a pair", 2);
}
