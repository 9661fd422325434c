// The MCAP format's constants (mcap.dev specification, version 0), shared by the reader
// (log_mcap.cpp) and the writer (log_mcap_writer.cpp).
#pragma once
#include <cstdint>

namespace cs::mcap {

constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

// Record opcodes.
enum Op : uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

}  // namespace cs::mcap
