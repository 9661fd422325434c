// The calibration readers' error contract, shared by their test files: a refusal is one
// line that starts with the file's name and names what was wrong.
#pragma once
#include <string>
#include <vector>

#include <doctest/doctest.h>
#include "curvestereo/image.hpp"  // cs::Error
#include "curvestereo/rig.hpp"

// The error a calibration text gets under the name "calib.txt" ("<no error>" if none).
inline std::string errorOf(const std::string& text) {
  try {
    cs::parseCalibration(text, "calib.txt");
  } catch (const cs::Error& e) {
    return e.what();
  }
  return "<no error>";
}

// One line, naming the file, containing every key word (the format recognised, the key).
inline void checkError(const std::string& text, const std::vector<std::string>& keyWords) {
  const std::string msg = errorOf(text);
  CAPTURE(msg);
  CHECK(msg.rfind("calib.txt: ", 0) == 0);
  CHECK(msg.find('\n') == std::string::npos);
  for (const auto& word : keyWords) {
    CAPTURE(word);
    CHECK(msg.find(word) != std::string::npos);
  }
}
