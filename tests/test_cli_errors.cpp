// The command line on bad input (issue 6): every case runs the built `curvestereo run`
// on files made here, and must exit non-zero with exactly one stderr line
// "curvestereo: error: <message>" naming the problem. A few inputs are handled rather
// than refused (colour, 16-bit, a uniformly rescaled pair with --scale-intrinsics).
// The cases and what the program said are written to cli_errors.md (a Markdown table)
// in the working directory, for the record.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "curvestereo/image_io.hpp"
#include "golden_cases.hpp"  // hash01
#include "test_util.hpp"

namespace fs = std::filesystem;
using namespace cs;

namespace {

// The CLI binary: build/tools/curvestereo next to build/tests/<this test>.
fs::path cliPath() {
  const fs::path self = fs::read_symlink("/proc/self/exe");
  return self.parent_path().parent_path() / "tools" / "curvestereo";
}

std::string readAll(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

void writeText(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

struct Outcome {
  int exitCode = -1;
  std::string out, err;
};

Outcome runCli(const fs::path& dir, const std::string& args) {
  const std::string cmd =
      "cd '" + dir.string() + "' && '" + cliPath().string() + "' " + args + " > stdout.txt 2> stderr.txt";
  const int status = std::system(cmd.c_str());
  Outcome o;
  o.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  o.out = readAll(dir / "stdout.txt");
  o.err = readAll(dir / "stderr.txt");
  return o;
}

ImageF noise(int w, int h, uint32_t seed) {
  ImageF img(w, h);
  for (size_t i = 0; i < img.size(); ++i) img.data[i] = golden::hash01(uint32_t(i) + seed * 0x9e3779b9u);
  return img;
}

// A 64x64 equidistant fisheye pair, 12 cm apart; fields that cases replace are spelled
// so each appears once per camera.
std::string camchain(int size = 64) {
  const double f = size / M_PI, c = 0.5 * (size - 1);
  std::ostringstream cam;
  cam.precision(10);
  cam << "  camera_model: pinhole\n  distortion_coeffs: [0.0, 0.0, 0.0, 0.0]\n  distortion_model: equidistant\n"
      << "  intrinsics: [" << f << ", " << f << ", " << c << ", " << c << "]\n  resolution: [" << size << ", " << size
      << "]\n";
  return "cam0:\n" + cam.str() +
         "cam1:\n  T_cn_cnm1:\n  - [1.0, 0.0, 0.0, -0.12]\n  - [0.0, 1.0, 0.0, 0.0]\n  - [0.0, 0.0, 1.0, 0.0]\n"
         "  - [0.0, 0.0, 0.0, 1.0]\n" +
         cam.str();
}

std::string replaceFirst(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  REQUIRE_MESSAGE(at != std::string::npos, "'" << from << "' not in the template");
  return text.replace(at, from.size(), to);
}

std::string replaceAll(std::string text, const std::string& from, const std::string& to) {
  for (size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
    text.replace(at, from.size(), to);
  return text;
}

// The PNG chunk checksum (ISO 3309 CRC-32), to forge a well-formed but absurd header.
uint32_t crc32(const char* data, size_t size) {
  uint32_t c = 0xffffffffu;
  for (size_t i = 0; i < size; ++i) {
    c ^= uint8_t(data[i]);
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
  }
  return c ^ 0xffffffffu;
}

struct Row {
  std::string input, message;
  int exitCode;
};

std::string cell(std::string s) {
  s = replaceAll(s, "|", "\\|");
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.pop_back();
  return replaceAll(s, "\n", " <br> ");
}

class Cases {
 public:
  explicit Cases(fs::path dir) : dir_(std::move(dir)) {}
  ~Cases() {
    std::ofstream md("cli_errors.md");
    md << "| input | what curvestereo said (stderr) | exit |\n|---|---|---|\n";
    for (const Row& r : rows_) md << "| " << cell(r.input) << " | " << cell(r.message) << " | " << r.exitCode << " |\n";
    MESSAGE("wrote " << (fs::current_path() / "cli_errors.md").string() << " (" << rows_.size() << " cases)");
  }

  // A bad input: non-zero exit, one stderr line "curvestereo: error: ..." containing needle.
  void refused(const std::string& input, const std::string& args, const std::string& needle) {
    CAPTURE(input);
    const Outcome o = runCli(dir_, args);
    rows_.push_back({input, o.err, o.exitCode});
    CHECK(o.exitCode != 0);
    CHECK(o.exitCode < 128);  // an exit, not a signal
    CHECK_MESSAGE(o.err.rfind("curvestereo: error: ", 0) == 0, o.err);
    CHECK_MESSAGE(std::count(o.err.begin(), o.err.end(), '\n') == 1, o.err);
    CHECK_MESSAGE(o.err.find(needle) != std::string::npos, o.err);
  }

  // An input that is handled: exit 0, and stderr mentions `note` when given.
  void handled(const std::string& input, const std::string& args, const std::string& note) {
    CAPTURE(input);
    const Outcome o = runCli(dir_, args);
    std::string notes;
    std::istringstream lines(o.err);
    for (std::string line; std::getline(lines, line);)
      if (line.find("note:") != std::string::npos) notes += (notes.empty() ? "" : "\n") + line;
    rows_.push_back({input, notes.empty() ? "(no message; solved)" : notes + " (solved)", o.exitCode});
    CHECK_MESSAGE(o.exitCode == 0, o.err);
    if (!note.empty()) CHECK_MESSAGE(notes.find(note) != std::string::npos, o.err);
    CHECK(fs::exists(dir_ / "out" / "depth.exr"));
    fs::remove_all(dir_ / "out");
  }

 private:
  fs::path dir_;
  std::vector<Row> rows_;
};

}  // namespace

TEST_CASE("curvestereo run: every bad input is one error line and a non-zero exit") {
  REQUIRE_MESSAGE(fs::exists(cliPath()), "build the curvestereo binary first: " << cliPath());
  const fs::path dir = test::tempDir("cli_errors");
  const std::string solve = " -o out --preset realtime --init none --levels 1 --warps 1 --iterations 2";

  // Good inputs to break one at a time.
  writeText(dir / "rig.yaml", camchain());
  writePngGray((dir / "l.png").string(), noise(64, 64, 1));
  writePngGray((dir / "r.png").string(), noise(64, 64, 2));
  const std::string good = "run --calib rig.yaml l.png r.png" + solve;
  REQUIRE_MESSAGE(runCli(dir, good).exitCode == 0, runCli(dir, good).err);
  fs::remove_all(dir / "out");

  auto rig = [&](const std::string& name, const std::string& text) {
    writeText(dir / name, text);
    return "run --calib " + name + " l.png r.png" + solve;
  };
  auto pair = [&](const std::string& left, const std::string& right) {
    return "run --calib rig.yaml " + left + " " + right + solve;
  };
  const std::string png = readAll(dir / "l.png");

  Cases cases(dir);
  // ---- image files
  cases.refused("left image missing", pair("nope.png", "r.png"), "No such file or directory");
  fs::create_directories(dir / "adir.png");
  cases.refused("left image is a directory", pair("adir.png", "r.png"), "Is a directory");
  writeText(dir / "empty.png", "");
  cases.refused("empty image file", pair("empty.png", "r.png"), "is not a PNG file");
  writeText(dir / "text.png", "hello, this is not an image\n");
  cases.refused("text file named .png", pair("text.png", "r.png"), "is not a PNG file");
  writeText(dir / "trunc.png", png.substr(0, png.size() / 2));
  cases.refused("PNG truncated to half", pair("l.png", "trunc.png"), "truncated");
  {
    std::string bad = png;
    bad[bad.size() / 2] = char(bad[bad.size() / 2] ^ 0x55);  // inside IDAT: CRC or zlib error
    writeText(dir / "flipped.png", bad);
    cases.refused("PNG with a corrupted byte in IDAT", pair("flipped.png", "r.png"), "corrupt PNG");
    std::string header = png;
    header[18] = char(0x9c), header[19] = char(0x40);    // IHDR width 40000, with a correct CRC
    const uint32_t crc = crc32(header.data() + 12, 17);  // chunk type + IHDR data
    for (int i = 0; i < 4; ++i) header[29 + i] = char(crc >> (24 - 8 * i));
    writeText(dir / "huge.png", header);
    cases.refused("PNG header claiming a 40000x64 image", pair("huge.png", "r.png"), "implausible size");
  }
  writeExr((dir / "depth.exr").string(), noise(64, 64, 3));
  cases.refused("an EXR given as the left image", pair("depth.exr", "r.png"), "is not a PNG file");

  // ---- sizes
  writePngGray((dir / "r48.png").string(), noise(48, 64, 4));
  cases.refused("left 64x64, right 48x64", pair("l.png", "r48.png"), "the pair must have the same size");
  writePngGray((dir / "l48.png").string(), noise(48, 64, 5));
  cases.refused("pair 48x64, calibration 64x64 (not a uniform rescale)", pair("l48.png", "r48.png"),
                "not a uniform rescale");
  writePngGray((dir / "l32.png").string(), noise(32, 32, 6));
  writePngGray((dir / "r32.png").string(), noise(32, 32, 7));
  cases.refused("half-resolution pair 32x32, calibration 64x64, no flag", pair("l32.png", "r32.png"),
                "pass --scale-intrinsics");
  cases.handled("half-resolution pair with --scale-intrinsics", pair("l32.png", "r32.png") + " --scale-intrinsics",
                "intrinsics scaled by 1/2");
  writePngGray((dir / "l8.png").string(), noise(8, 8, 8));
  writePngGray((dir / "r8.png").string(), noise(8, 8, 9));
  writeText(dir / "rig8.yaml", camchain(8));
  cases.refused("8x8 pair and calibration (below the minimum)", "run --calib rig8.yaml l8.png r8.png" + solve,
                "too small (at least 16x16)");
  writePngGray((dir / "mask.png").string(), noise(32, 32, 10));
  cases.refused("--mask of another size", good + " --mask mask.png", "mask is 32x32 but the images are 64x64");

  // ---- handled formats
  writePngGray16((dir / "l16.png").string(), noise(64, 64, 1));
  writePngGray16((dir / "r16.png").string(), noise(64, 64, 2));
  cases.handled("16-bit gray pair", pair("l16.png", "r16.png"), "");
  Image<uint32_t> rgb(64, 64);
  for (size_t i = 0; i < rgb.size(); ++i) rgb.data[i] = uint32_t(i * 2654435761u) & 0xffffff;
  writePngRgb((dir / "rgb.png").string(), rgb);
  cases.handled("8-bit RGB left image", pair("rgb.png", "r.png"), "converted to gray");

  // ---- calibration
  cases.refused("calibration file missing", "run --calib none.yaml l.png r.png" + solve, "does not exist");
  cases.refused("calibration not YAML", rig("bad_syntax.yaml", "cam0: [1, 2\ncam1: {"), "YAML syntax error");
  cases.refused("calibration is a list", rig("list.yaml", "- 1\n- 2\n"), "not a Kalibr camchain");
  cases.refused("camera_model 'fisheye'", rig("model.yaml", replaceFirst(camchain(), "pinhole", "fisheye")),
                "unknown camera_model 'fisheye'");
  cases.refused("distortion_model 'fov'", rig("dist.yaml", replaceFirst(camchain(), "equidistant", "fov")),
                "unsupported camera model pinhole+fov");
  cases.refused("omni with equidistant distortion",
                rig("omni_eq.yaml", replaceFirst(camchain(), "camera_model: pinhole", "camera_model: omni")),
                "unsupported camera model omni+equidistant");
  cases.refused("cam0.intrinsics missing",
                rig("nointr.yaml", replaceFirst(camchain(), "  intrinsics:", "  intrinsic_typo:")),
                "missing key \"cam0.intrinsics\"");
  cases.refused("cam1 missing", rig("nocam1.yaml", camchain().substr(0, camchain().find("cam1:"))),
                "missing key \"cam1\"");
  cases.refused("T_cn_cnm1 missing", rig("noT.yaml", replaceFirst(camchain(), "  T_cn_cnm1:", "  T_typo:")),
                "T_cn_cnm1");
  cases.refused("intrinsics with a word in it", rig("word.yaml", replaceFirst(camchain(), "[20.", "[twenty, 20.")),
                "is not a number ('twenty')");
  cases.refused("intrinsics with 5 values",
                rig("five.yaml", replaceFirst(camchain(), "intrinsics: [", "intrinsics: [1.0, ")),
                "needs 4 [fu fv pu pv]");
  cases.refused("fx = .nan",
                rig("nan.yaml", replaceFirst(camchain(), "intrinsics: [", "intrinsics: [.nan, 1, 1, 1] #")),
                "fx is not finite");
  cases.refused("fy = .inf",
                rig("inf.yaml", replaceFirst(camchain(), "intrinsics: [", "intrinsics: [20, .inf, 31.5, 31.5] #")),
                "fy is not finite");
  cases.refused("negative focal length",
                rig("negf.yaml", replaceFirst(camchain(), "intrinsics: [", "intrinsics: [-20, 20, 31.5, 31.5] #")),
                "is not positive");
  cases.refused("fx = 0.02 (focal length in metres)",
                rig("metres.yaml", replaceFirst(camchain(), "intrinsics: [", "intrinsics: [0.02, 20, 31.5, 31.5] #")),
                "fx = 0.02 px is absurd");
  cases.refused("principal point 10^5 px away",
                rig("cx.yaml", replaceFirst(camchain(), "intrinsics: [", "intrinsics: [20, 20, 100000, 31.5] #")),
                "far outside the image");
  cases.refused("distortion k1 = .nan",
                rig("k1.yaml", replaceFirst(camchain(), "distortion_coeffs: [0.0", "distortion_coeffs: [.nan")),
                "k1 is not finite");
  cases.refused("resolution [0, 64]", rig("res0.yaml", replaceFirst(camchain(), "resolution: [64", "resolution: [0")),
                "resolution must hold two positive integers");
  cases.refused("resolution [64.5, 64]",
                rig("resfrac.yaml", replaceFirst(camchain(), "resolution: [64", "resolution: [64.5")),
                "resolution must hold two positive integers");
  {
    std::string ds = replaceFirst(camchain(), "camera_model: pinhole", "camera_model: ds");
    ds = replaceFirst(ds, "distortion_coeffs: [0.0, 0.0, 0.0, 0.0]", "distortion_coeffs: []");
    ds = replaceFirst(ds, "distortion_model: equidistant", "distortion_model: none");
    ds = replaceFirst(ds, "intrinsics: [", "intrinsics: [-0.2, 2.0, 20, 20, 31.5, 31.5] #");
    cases.refused("double sphere with alpha = 2", rig("ds.yaml", ds), "alpha = 2 is outside [0, 1]");
  }
  cases.refused("rotation scaled by 1.01",
                rig("scaledR.yaml", replaceFirst(camchain(), "- [1.0, 0.0, 0.0, -0.12]", "- [1.01, 0.0, 0.0, -0.12]")),
                "rotation is not a rotation");
  cases.refused("rotation is a reflection (det = -1)",
                rig("reflect.yaml", replaceFirst(camchain(), "- [0.0, 0.0, 1.0, 0.0]", "- [0.0, 0.0, -1.0, 0.0]")),
                "rotation is not a rotation (det=-1");
  cases.refused("T_cn_cnm1 is 3x4", rig("t34.yaml", replaceFirst(camchain(), "  - [0.0, 0.0, 0.0, 1.0]\n", "")),
                "must be a 4x4 matrix");
  cases.refused("T_cn_cnm1 last row [0, 0, 0, 2]",
                rig("lastrow.yaml", replaceFirst(camchain(), "- [0.0, 0.0, 0.0, 1.0]", "- [0.0, 0.0, 0.0, 2.0]")),
                "last row must be [0, 0, 0, 1]");
  cases.refused("zero baseline", rig("zero.yaml", replaceFirst(camchain(), "-0.12]", "0.0]")), "zero baseline");
  cases.refused("baseline of 1e-9 m", rig("tiny.yaml", replaceFirst(camchain(), "-0.12]", "1e-9]")), "zero baseline");
  cases.refused("translation .inf", rig("tinf.yaml", replaceFirst(camchain(), "-0.12]", ".inf]")), "non-finite");

  // ---- options
  cases.refused("unknown option", good + " --wraps 3", "unknown option --wraps");
  cases.refused("--warps not a number", good + " --warps many", "expects an integer, got 'many'");
  cases.refused("--warps 4294967297 (overflows int)", good + " --warps 4294967297", "expects an integer");
  cases.refused("--lambda nan", good + " --lambda nan", "expects a number");
  cases.refused("--warps 0", good + " --warps 0", "warps must be in [1, 1000]");
  cases.refused("--max-fov 400", good + " --max-fov 400", "maxFovDeg must be in [0, 360]");
  cases.refused("unknown preset", good + " --preset fastest", "unknown preset 'fastest'");
  cases.refused("unknown backend", good + " --backend tpu", "tpu");
  cases.refused("one image only", "run --calib rig.yaml l.png" + solve, "exactly two images");
  writeText(dir / "not_a_folder", "a file where the outputs would go\n");
  cases.refused("-o names an existing file", "run --calib rig.yaml l.png r.png -o not_a_folder --levels 1",
                "-o not_a_folder: is an existing file, not a folder");
  CHECK(readAll(dir / "not_a_folder") == "a file where the outputs would go\n");  // untouched
  cases.refused("bench --runs 0", "bench --calib rig.yaml l.png r.png --runs 0 --backend cpu", "--runs must be >= 1");
  cases.refused("bench --runs -3", "bench --calib rig.yaml l.png r.png --runs -3 --backend cpu", "--runs must be >= 1");

  // ---- the camera model of synth and demo (refused before anything is rendered)
  const std::string synth = "synth -o synth_out --size 32 --samples 1 --quiet";
  cases.refused("synth --camera d435", synth + " --camera d435", "unknown camera model 'd435' (known: none, t265)");
  cases.refused("synth --shot -1", synth + " --camera t265 --shot -1", "shot noise (--shot");
  cases.refused("synth --read -0.5", synth + " --read -0.5", "read noise (--read");
  cases.refused("synth --bits 12", synth + " --camera t265 --bits 12", "--bits must be 8 or 16, got 12");
  cases.refused("synth --vignette 0", synth + " --vignette 0",
                "vignette rim (--vignette, --vignette-left) must be in (0");
  cases.refused("synth --vignette-right 1.5", synth + " --vignette-right 1.5", "must be in (0, 1], got 1.5");
  cases.refused("synth --exposure nan", synth + " --exposure nan", "option --exposure expects a number, got 'nan'");
  cases.refused("synth --exposure 2", synth + " --exposure 2", "the exposure (--exposure");
  cases.refused("synth --gain-right 0", synth + " --gain-right 0", "gain (--gain-right)");
  cases.refused("synth --camera-gamma -1", synth + " --camera-gamma -1", "gamma (--camera-gamma)");
  cases.refused("synth --vignette-mode cos4", synth + " --vignette-mode cos4", "unknown vignette mode 'cos4'");
  cases.refused("synth --noise-seed -1", synth + " --camera t265 --noise-seed -1",
                "--noise-seed expects a non-negative");
  cases.refused("demo --camera t265 --blur -1", "demo -o demo_out --size 32 --camera t265 --blur -1",
                "blur sigma (--blur");
  CHECK(!fs::exists(dir / "synth_out"));  // nothing written for a refused model

  // ---- the plane-sweep initialiser
  cases.handled("--min-confidence without the initialiser", good + " --min-confidence 0.5", "");
  cases.refused("--min-confidence 2", good + " --init planesweep --min-confidence 2",
                "--min-confidence must be in [0, 1]");
  cases.refused("--min-confidence -0.1 with the initialiser", good + " --init planesweep --min-confidence -0.1",
                "--min-confidence must be in [0, 1]");
  cases.refused("--init foo", good + " --init foo", "unknown initialisation 'foo' (known: none, planesweep)");
  cases.refused("--init-radius 9", good + " --init planesweep --init-radius 9", "initRadius must be in [1, 7]");
  cases.refused("--init-p2 below --init-p1", good + " --init planesweep --init-p1 0.2 --init-p2 0.1",
                "initP1, initP2 must satisfy 0 <= initP1 <= initP2");
  cases.refused("--occlusion-weight 2", good + " --init planesweep --occlusion-weight 2",
                "occlusionWeight must be in [0, 1]");
  cases.handled("--init planesweep --min-confidence 0.5", good + " --init planesweep --min-confidence 0.5", "");
  {
    // handled() removed the output: run again to look at it.
    REQUIRE(runCli(dir, good + " --init planesweep --min-confidence 0.5").exitCode == 0);
    const ImageF confidence = readExr((dir / "out" / "confidence.exr").string());
    CHECK(confidence.width == 64);
    CHECK(fs::exists(dir / "out" / "confidence.png"));
    fs::remove_all(dir / "out");
    REQUIRE(runCli(dir, good).exitCode == 0);
    CHECK(fs::exists(dir / "out" / "confidence.exr"));  // every preset has a confidence
    fs::remove_all(dir / "out");
  }
}
