// libFuzzer target: the ros1 log reader through cs::Sequence::openLog (topics /cam0/image_raw
// and /cam1/image_raw, as the seeds in corpus/log_ros1/ have them) and cs::logInfo, then
// every frame's images decoded. Each must succeed or throw a one-line cs::Error.
#include "fuzz_log.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  cs::fuzz::readLog(cs::fuzz::writeScratch(data, size, ".bag"));
  return 0;
}
