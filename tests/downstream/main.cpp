// Uses only the installed public API: writes a small Kalibr camchain, reads it back
// (cs::loadCalibration, cs::loadKalibr), solves a synthetic pair on the CPU backend
// (cs::preset, cs::Stereo) and prints one line. Exit status 0 when it solved pixels.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "curvestereo/image.hpp"
#include "curvestereo/params.hpp"
#include "curvestereo/rig.hpp"
#include "curvestereo/stereo.hpp"
#ifdef CS_HAVE_CUDA
#include "curvestereo/cuda.hpp"  // installed with the CUDA backend; must compile here too
#endif

int main(int argc, char** argv) {
  const std::string path = argc > 1 ? argv[1] : "downstream_camchain.yaml";
  const int size = 96;
  {
    // Two equidistant fisheye cameras 10 cm apart along x.
    const char* cam =
        "  camera_model: pinhole\n"
        "  distortion_coeffs: [0.0, 0.0, 0.0, 0.0]\n"
        "  distortion_model: equidistant\n"
        "  intrinsics: [30.0, 30.0, 47.5, 47.5]\n"
        "  resolution: [96, 96]\n";
    std::ofstream out(path);
    out << "cam0:\n"
        << cam << "cam1:\n"
        << "  T_cn_cnm1:\n  - [1.0, 0.0, 0.0, -0.1]\n  - [0.0, 1.0, 0.0, 0.0]\n"
        << "  - [0.0, 0.0, 1.0, 0.0]\n  - [0.0, 0.0, 0.0, 1.0]\n"
        << cam;
  }
  try {
    const cs::Rig rig = cs::loadCalibration(path);
    const cs::Rig same = cs::loadKalibr(path);
    if (same.cam0.width != rig.cam0.width) throw cs::Error("loadKalibr and loadCalibration disagree");

    cs::Stereo stereo(rig, cs::preset("realtime"), "cpu");
    // A textured pair: the right image is the left one moved 2 px (roughly along the
    // epipolar curves near the centre).
    cs::ImageF left(size, size), right(size, size);
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) {
        auto texture = [&](double u) { return float(0.5 + 0.25 * std::sin(0.7 * u) * std::cos(0.45 * y)); };
        left(x, y) = texture(x);
        right(x, y) = texture(x + 2.0);
      }
    const cs::DepthResult r = stereo.compute(left, right);
    int solved = 0;
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) solved += r.valid(x, y) ? 1 : 0;
    std::printf("downstream: %s backend %s, %dx%d frame, %d pixels solved, %.1f ms\n", path.c_str(),
                stereo.backendName().c_str(), size, size, solved, r.totalMs);
    return solved > 0 ? 0 : 1;
  } catch (const cs::Error& e) {
    std::fprintf(stderr, "downstream: %s\n", e.what());
    return 1;
  }
}
