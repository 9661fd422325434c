// run --sequence end to end on a sequence synth renders: the outputs of every frame, the
// summary, and bad input mid-sequence (one line naming the frame, the frames before it kept).
#include <cstdio>
#include <filesystem>
#include <string>

#include "cli_util.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using namespace cs::test;

namespace {

// 4 frames of 96 px; solved on the CPU with 3 levels (the band sweep at level 1 below a
// full sweep at 2), so the warm frames happen.
const char* kSolve = "--backend cpu --levels 3 --min-width 16";

fs::path renderSequence(const fs::path& dir) {
  const CliOutcome synth = runCli(dir, "synth --sequence -o seq --frames 4 --size 96 --samples 1 --quiet");
  REQUIRE(synth.exitCode == 0);
  return dir / "seq";
}

// The i-th frame's image of camera `cam`.
fs::path frameImage(const fs::path& seq, int cam, int i) {
  std::vector<fs::path> images;
  for (const auto& e : fs::directory_iterator(seq / "mav0" / ("cam" + std::to_string(cam)) / "data"))
    images.push_back(e.path());
  std::sort(images.begin(), images.end());
  return images.at(size_t(i));
}

size_t folders(const fs::path& dir) {
  size_t n = 0;
  for (const auto& e : fs::directory_iterator(dir)) n += e.is_directory();
  return n;
}

}  // namespace

TEST_CASE("run --sequence: every frame's outputs under its timestamp, warm after the first") {
  const fs::path dir = tempDir("cli_sequence");
  renderSequence(dir);
  const CliOutcome r = runCli(dir, std::string("run --sequence seq -o out ") + kSolve);
  INFO(r.err);
  REQUIRE(r.exitCode == 0);
  CHECK(r.out.find("4 stereo frames (ASL, 4 with poses)") != std::string::npos);
  CHECK(r.out.find("(warm 3,") != std::string::npos);
  CHECK(r.out.find("cold 1,") != std::string::npos);
  CHECK(folders(dir / "out") == 4);
  CHECK(r.out.find("the solving thread waited") != std::string::npos);  // the reading cost, said
  CHECK(fs::is_regular_file(dir / "out/1000033333333/depth.exr"));
  CHECK(fs::is_regular_file(dir / "out/1000033333333/depth.png"));
  // --frames: a part of the recording alone (frames 1 and 2 of 0..3).
  const CliOutcome part = runCli(dir, std::string("run --sequence seq -o part --frames 1:3 ") + kSolve);
  INFO(part.err);
  CHECK(part.exitCode == 0);
  CHECK(folders(dir / "part") == 2);
  CHECK(fs::is_directory(dir / "part/1000033333333"));
  CHECK(fs::is_directory(dir / "part/1000066666667"));
  CHECK(runCli(dir, std::string("run --sequence seq -o part2 --frames 3: ") + kSolve).exitCode == 0);
  CHECK(folders(dir / "part2") == 1);
  const CliOutcome past = runCli(dir, std::string("run --sequence seq -o past --frames 4: ") + kSolve);
  CHECK(past.exitCode == 1);
  CHECK(past.err.find("--frames 4:: the sequence has 4 frames (0 to 3)") != std::string::npos);
  CHECK_FALSE(fs::exists(dir / "past/1000000000000"));
  CHECK(runCli(dir, std::string("run --sequence seq -o bad --frames 2:2 ") + kSolve).exitCode == 2);
  // --cold: the baseline, every frame alone.
  const CliOutcome cold = runCli(dir, std::string("run --sequence seq -o cold --cold ") + kSolve);
  CHECK(cold.exitCode == 0);
  CHECK(cold.out.find("(warm 0,") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("run --sequence: a missing or resized frame stops the run in one line, earlier frames kept") {
  const fs::path dir = tempDir("cli_sequence_bad");
  const fs::path seq = renderSequence(dir);
  fs::remove(frameImage(seq, 1, 2));
  CliOutcome r;
  // Read ahead by 1 and 3 threads: frame 2's error comes at its turn, the frames before it written.
  for (const char* threads : {" --read-threads 1", " --read-threads 3"}) {
    fs::remove_all(dir / "out");
    r = runCli(dir, std::string("run --sequence seq -o out ") + kSolve + threads);
    CHECK(r.exitCode == 1);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 2);  // the calibration note and the error
    CHECK(r.err.find("frame 2 (t 1000066666667 ns), right image: cannot open image") != std::string::npos);
    CHECK(r.err.find("(2 frames before it are written)") != std::string::npos);
    CHECK(folders(dir / "out") == 2);
  }
  r = runCli(dir, std::string("run --sequence seq -o bad --read-threads x ") + kSolve);
  CHECK(r.exitCode == 2);
  CHECK(r.err.find("--read-threads expects a whole number") != std::string::npos);

  // Both images of frame 2 at another size than the calibration's.
  const CliOutcome big = runCli(dir, "synth -o big --size 128 --samples 1 --quiet");
  REQUIRE(big.exitCode == 0);
  fs::copy_file(dir / "big/left.png", frameImage(seq, 0, 2), fs::copy_options::overwrite_existing);
  fs::copy_file(dir / "big/right.png", frameImage(seq, 0, 2).parent_path().parent_path().parent_path() / "cam1/data" /
                                           frameImage(seq, 0, 2).filename());
  fs::remove_all(dir / "out");
  r = runCli(dir, std::string("run --sequence seq -o out ") + kSolve);
  CHECK(r.exitCode == 1);
  CHECK(r.err.find("frame 2 (t 1000066666667 ns): left image is 128x128 but the calibration says 96x96") !=
        std::string::npos);
  CHECK(folders(dir / "out") == 2);

  // A corrupt data.csv is refused before any frame is solved.
  {
    std::ofstream csv(seq / "mav0/cam0/data.csv", std::ios::app);
    csv << "not-a-time,x.png\n";
  }
  fs::remove_all(dir / "out");
  r = runCli(dir, std::string("run --sequence seq -o out ") + kSolve);
  CHECK(r.exitCode == 1);
  CHECK(r.err.find("data.csv line 6: timestamp 'not-a-time' is not an integer") != std::string::npos);
  CHECK_FALSE(fs::exists(dir / "out/1000000000000"));
  fs::remove_all(dir);
}

// Issue 27's measure on the first frames of the shared clean sequence (plain walls and floor,
// where no data corrects a carried error): warm frames as accurate as cold ones (+0.3 points
// of mean tau>1 at most) and at most half the flicker. A warm start that let the carried
// estimate drift lost half a point a frame there (+0.8 over 6 frames). 8 frames: the
// filter needs a few to settle (with band 16 and 4 coarse warps, x0.51 over the first 6
// frames, x0.47 over 8). Now -2.38 points, x0.40 over 8; the CPU oracle gives the same
// figures on every run.
TEST_CASE("eval --sequence --compare: warm frames no worse than cold on seqD1's plain surfaces, half the flicker") {
  if (CS_SANITIZED) {
    // A measure of accuracy, about ten times slower under the sanitizers; the code paths it
    // runs are the synth sequence's above.
    MESSAGE("skipped in the sanitizer build");
    return;
  }
  const std::string seq = sharedData("sequences/seqD1_indoor_walk");
  if (seq.empty()) {
    MESSAGE("skipped: ../shared/data/sequences/seqD1_indoor_walk not present");
    return;
  }
  const fs::path dir = tempDir("cs_eval_seqD1");
  const CliOutcome r = runCli(dir, "eval --sequence " + seq + " --compare --frames 8 --backend cpu");
  CAPTURE(r.err);
  REQUIRE(r.exitCode == 0);
  const size_t at = r.out.find("judged ");
  REQUIRE(at != std::string::npos);
  double flickerRatio = 0, deltaTau = 0, deltaMover = 0;
  const std::string line = r.out.substr(r.out.find(':', at) + 1);
  REQUIRE(std::sscanf(line.c_str(), " flicker warm/cold %lf, delta mean tau>1 %lf, delta mover tau>1 %lf",
                      &flickerRatio, &deltaTau, &deltaMover) == 3);
  MESSAGE("flicker warm/cold " << flickerRatio << ", delta tau>1 " << deltaTau << ", delta mover " << deltaMover);
  CHECK(deltaTau <= 0.3);
  CHECK(flickerRatio <= 0.5);
  CHECK(deltaMover <= 1.0);
}
