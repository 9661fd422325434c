// The top-level entries of an OpenCV FileStorage file, from YAML or XML alike, so that
// one reader turns either into a Rig. Private to core/src.
#pragma once
#include <map>
#include <string>
#include <vector>

namespace cs::calib {

struct CvValue {
  enum class Kind { Scalar, Matrix, List, Other };
  Kind kind = Kind::Other;
  std::string text;          // Scalar: the text (quotes removed)
  int rows = 0, cols = 0;    // Matrix: its shape
  std::vector<double> data;  // Matrix: rows * cols values, row by row; List: its numbers
  std::string where;         // " (line N)" where known, for messages
};

using CvStorage = std::map<std::string, CvValue>;

// The entries of <opencv_storage>: an element with <rows>, <cols> and <data> children is a
// matrix; one with only text a scalar; anything else Kind::Other. Throws cs::Error
// "<name>: XML syntax error at line N: ..." or "<name>: ..." for a matrix that does not
// add up (rows * cols values).
CvStorage parseOpenCvXml(const std::string& text, const std::string& name);

// Whitespace- or comma-separated numbers; false on anything else (empty text included).
bool parseNumberList(const std::string& text, std::vector<double>& out);

// Text with &, <, >, " escaped for XML.
std::string xmlEscape(const std::string& text);

}  // namespace cs::calib
