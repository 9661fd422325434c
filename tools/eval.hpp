// The pieces of `curvestereo eval` shared by its files: a pair with ground truth and a
// result row (cmd_eval.cpp: the command, its methods and pairs), the CSV and Markdown
// tables (eval_report.cpp), the per-pair picture sheet (eval_sheet.cpp) and the paper's
// warps / du_max parameter study (eval_study.cpp); sequences (eval_sequence.cpp).
#pragma once
#include <string>
#include <vector>

#include "args.hpp"
#include "curvestereo/image.hpp"
#include "curvestereo/metrics.hpp"
#include "curvestereo/params.hpp"
#include "curvestereo/rig.hpp"

namespace cs::cli::eval {

// One method on one pair.
struct Row {
  std::string pair, method;
  Metrics m;
  double ms;
  double tau1Est = 0, tau3Est = 0;  // over pixels with an estimate only (the paper's planesweep-valid convention)
};

struct Pair {
  std::string dir, name;
  Rig rig;
  ImageF left, right, depthLeft, depthRight;
};

// A pair folder: camchain.yaml, left.png, right.png, depth_left.exr [, depth_right.exr].
Pair loadPair(const std::string& dir);

// "a,b,c" -> {a, b, c} (empty items dropped); numberList throws naming --option.
std::vector<std::string> splitList(const std::string& s);
std::vector<double> numberList(const std::string& s, const char* option);
std::string fovName(double fov);

// tau>k in percent over an error map (NaN: not evaluated). An infinite error is an evaluated
// pixel without an estimate: a bad pixel (Missing::Bad), or left out (Missing::Skipped, the
// paper's convention for planesweep-valid).
enum class Missing { Bad, Skipped };
double tauPercent(const ImageF& error, double k, Missing missing);

void writeCsv(const std::string& path, const std::vector<Row>& rows);
std::string markdown(const std::vector<Row>& rows, const Params& params, const Args& args);

// One method's column of a pair's sheet.
struct SheetEntry {
  std::string method;
  const ImageF* depth;
  const ImageF* error;
  double tau1, tau3;
};
// Writes DIR/<pair>_sheet.png (input and ground truth, then each method's depth over its
// error) and each method's error and depth pictures.
void writeSheet(const std::string& dir, const Pair& p, const std::vector<SheetEntry>& entries);

// --sparsification FILE (eval_sparsification.cpp): one line per pair, and every pair's curve
// in the CSV FILE with the mean curves beside the oracle's in FILE's .png.
void printSparsification(const std::string& pair, const Sparsification& s);
void writeSparsification(const std::string& path, const std::vector<std::pair<std::string, Sparsification>>& curves);

// --sweep warps=A..B | dumax=A..B: the paper's two parameter studies as CSV and a plot.
int runStudy(const Args& args, const Params& base, const std::string& backend);

// --sequence DIR [DIR...]: sequences with ground truth (ASL folders: mav0/cam0, cam1, depth0
// [, depth1, mover0], poses_cam0.csv, camchain.yaml) run through Stereo::next, warm (the
// default), --cold (warm start and temporal filter off) or --compare (cold, then warm):
// per-frame tau, the moving object's tau>1 and the flicker (metrics.hpp), a summary per run,
// --csv / --md when asked (eval_sequence.cpp).
int runSequences(const Args& args, const Params& params, const std::string& backend);

}  // namespace cs::cli::eval
