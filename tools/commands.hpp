// The sub-commands of `curvestereo`. Each returns the process exit code; errors are
// thrown as cs::Error and printed as one line by main().
#pragma once
#include "args.hpp"

namespace cs::cli {

int cmdRun(const Args& args);
int cmdDemo(const Args& args);
int cmdSynth(const Args& args);
int cmdEval(const Args& args);
int cmdFields(const Args& args);
int cmdBench(const Args& args);
int cmdCalib(const Args& args);
int cmdLog(const Args& args);

}  // namespace cs::cli
