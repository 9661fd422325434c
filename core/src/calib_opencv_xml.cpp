// A small XML reader for OpenCV FileStorage files: elements, attributes, text, comments,
// the <?xml?> prolog and the five predefined entities plus numeric character references.
// No DTDs, namespaces or CDATA: OpenCV writes none of them. There is no XML library among
// the dependencies, and an OpenCV stereo calibration needs only this much.
#include <cctype>
#include <charconv>
#include <memory>
#include <string>
#include <vector>

#include "calib_common.hpp"
#include "calib_opencv.hpp"

namespace cs::calib {

namespace {

struct XmlElement {
  std::string name;
  std::string typeId;  // the type_id attribute ("opencv-matrix"), the only one used
  std::string text;    // character data directly inside, entities decoded
  std::vector<XmlElement> children;
  int line = 0;
};

class XmlParser {
 public:
  XmlParser(const std::string& text, const std::string& name) : s_(text), name_(name) {}

  XmlElement parseDocument() {
    if (s_.compare(0, 3, "\xEF\xBB\xBF") == 0) pos_ = 3;
    skipMisc();
    if (!at('<')) fail("expected the root element <opencv_storage>");
    XmlElement root = parseElement(0);
    skipMisc();
    if (pos_ < s_.size()) fail("text after the root element");
    return root;
  }

 private:
  // Deep enough for any FileStorage file; bounded so hostile input cannot exhaust the stack.
  static constexpr int kMaxDepth = 64;
  const std::string& s_;
  const std::string& name_;
  size_t pos_ = 0;
  mutable size_t countedTo_ = 0;
  mutable int countedLines_ = 1;

  [[noreturn]] void fail(const std::string& problem) const {
    throw Error(oneLine(name_ + ": XML syntax error at line " + std::to_string(lineAt(pos_)) + ": " + problem));
  }

  // Positions asked for only grow, so counting on from the last one keeps this linear.
  int lineAt(size_t p) const {
    if (p < countedTo_) countedTo_ = 0, countedLines_ = 1;
    for (; countedTo_ < p && countedTo_ < s_.size(); ++countedTo_) countedLines_ += s_[countedTo_] == '\n';
    return countedLines_;
  }

  bool at(char c) const { return pos_ < s_.size() && s_[pos_] == c; }
  bool startsWith(const char* text) const { return s_.compare(pos_, std::char_traits<char>::length(text), text) == 0; }
  void skipSpace() {
    while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
  }

  void skipPast(const char* end, const char* what) {
    const size_t found = s_.find(end, pos_);
    if (found == std::string::npos) fail(std::string("unterminated ") + what);
    pos_ = found + std::char_traits<char>::length(end);
  }

  // Whitespace, comments, processing instructions and <!DOCTYPE ...> outside elements.
  void skipMisc() {
    for (;;) {
      skipSpace();
      if (startsWith("<!--")) {
        skipPast("-->", "comment");
      } else if (startsWith("<?")) {
        skipPast("?>", "processing instruction");
      } else if (startsWith("<!")) {
        skipPast(">", "declaration");
      } else {
        return;
      }
    }
  }

  static bool isNameChar(char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.' || c == ':' ||
           static_cast<unsigned char>(c) >= 0x80;
  }

  std::string parseName() {
    const size_t start = pos_;
    while (pos_ < s_.size() && isNameChar(s_[pos_])) ++pos_;
    if (pos_ == start) fail("expected a name");
    return s_.substr(start, pos_ - start);
  }

  std::string decodeEntity() {
    const size_t end = s_.find(';', pos_);
    if (end == std::string::npos || end - pos_ > 12) fail("bad entity (an '&' not followed by name;)");
    const std::string entity = s_.substr(pos_ + 1, end - pos_ - 1);
    pos_ = end + 1;
    if (entity == "lt") return "<";
    if (entity == "gt") return ">";
    if (entity == "amp") return "&";
    if (entity == "quot") return "\"";
    if (entity == "apos") return "'";
    if (entity.size() > 1 && entity[0] == '#') {
      const bool hex = entity[1] == 'x';
      unsigned code = 0;
      const char* first = entity.data() + (hex ? 2 : 1);
      const char* last = entity.data() + entity.size();
      const auto r = std::from_chars(first, last, code, hex ? 16 : 10);
      // Only ASCII: calibration files hold numbers and model names.
      if (r.ec == std::errc() && r.ptr == last && first != last && code > 0 && code < 0x80)
        return std::string(1, char(code));
    }
    fail("unsupported entity &" + entity + ";");
  }

  std::string parseAttributeValue() {
    if (!at('"') && !at('\'')) fail("attribute value must be quoted");
    const char quote = s_[pos_++];
    std::string value;
    while (pos_ < s_.size() && s_[pos_] != quote) {
      if (s_[pos_] == '<') fail("'<' in an attribute value");
      if (s_[pos_] == '&') {
        value += decodeEntity();
      } else {
        value += s_[pos_++];
      }
    }
    if (!at(quote)) fail("unterminated attribute value");
    ++pos_;
    return value;
  }

  // After the name: attributes up to '>' or "/>". Returns true for an empty element.
  bool parseAttributes(XmlElement& e) {
    for (;;) {
      skipSpace();
      if (startsWith("/>")) {
        pos_ += 2;
        return true;
      }
      if (at('>')) {
        ++pos_;
        return false;
      }
      const std::string attr = parseName();
      skipSpace();
      if (!at('=')) fail("expected '=' after attribute " + attr);
      ++pos_;
      skipSpace();
      const std::string value = parseAttributeValue();
      if (attr == "type_id") e.typeId = value;
    }
  }

  XmlElement parseElement(int depth) {
    if (depth > kMaxDepth) fail("elements nested too deeply");
    XmlElement e;
    e.line = lineAt(pos_);
    ++pos_;  // '<'
    e.name = parseName();
    if (parseAttributes(e)) return e;
    parseContent(e, depth);
    return e;
  }

  // Text and children up to the matching end tag.
  void parseContent(XmlElement& e, int depth) {
    for (;;) {
      if (pos_ >= s_.size()) fail("missing </" + e.name + ">");
      if (startsWith("</")) {
        pos_ += 2;
        const std::string closing = parseName();
        if (closing != e.name) fail("</" + closing + "> closes <" + e.name + ">");
        skipSpace();
        if (!at('>')) fail("expected '>' after </" + closing);
        ++pos_;
        return;
      }
      if (startsWith("<!--")) {
        skipPast("-->", "comment");
      } else if (startsWith("<![CDATA[")) {
        fail("CDATA sections are not supported");
      } else if (startsWith("<?")) {
        skipPast("?>", "processing instruction");
      } else if (at('<')) {
        e.children.push_back(parseElement(depth + 1));
      } else if (at('&')) {
        e.text += decodeEntity();
      } else {
        e.text += s_[pos_++];
      }
    }
  }
};

std::string trimmed(const std::string& text) {
  size_t a = 0, b = text.size();
  while (a < b && std::isspace(static_cast<unsigned char>(text[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(text[b - 1]))) --b;
  return text.substr(a, b - a);
}

const XmlElement* child(const XmlElement& e, const char* name) {
  for (const XmlElement& c : e.children)
    if (c.name == name) return &c;
  return nullptr;
}

// <rows>, <cols>, <data>: a matrix whose values must add up to rows * cols.
CvValue matrixValue(const XmlElement& e, const std::string& name) {
  CvValue v;
  v.kind = CvValue::Kind::Matrix;
  v.where = " (line " + std::to_string(e.line) + ")";
  std::vector<double> shape;
  for (const char* dim : {"rows", "cols"}) {
    std::vector<double> n;
    if (!parseNumberList(child(e, dim)->text, n) || n.size() != 1 || !wholeInRange(n[0], 0, 1e6))
      throw Error(oneLine(name + ": " + e.name + "." + dim + " must be a whole number" + v.where));
    shape.push_back(n[0]);
  }
  v.rows = int(shape[0]);
  v.cols = int(shape[1]);
  if (!parseNumberList(child(e, "data")->text, v.data))
    throw Error(oneLine(name + ": " + e.name + ".data must hold numbers" + v.where));
  if (double(v.data.size()) != shape[0] * shape[1])
    throw Error(oneLine(name + ": " + e.name + " is " + std::to_string(v.rows) + "x" + std::to_string(v.cols) +
                        " but its data has " + std::to_string(v.data.size()) + " values" + v.where));
  return v;
}

CvValue entryValue(const XmlElement& e, const std::string& name) {
  const bool matrix = child(e, "rows") && child(e, "cols") && child(e, "data");
  if (matrix) return matrixValue(e, name);
  CvValue v;
  v.where = " (line " + std::to_string(e.line) + ")";
  if (!e.children.empty()) return v;  // Kind::Other: nested maps and sequences are not used
  v.kind = CvValue::Kind::Scalar;
  v.text = trimmed(e.text);
  // OpenCV quotes strings that would otherwise read as numbers or hold spaces.
  if (v.text.size() >= 2 && v.text.front() == '"' && v.text.back() == '"') v.text = v.text.substr(1, v.text.size() - 2);
  return v;
}

}  // namespace

bool parseNumberList(const std::string& text, std::vector<double>& out) {
  out.clear();
  const char* p = text.data();
  const char* end = p + text.size();
  for (;;) {
    while (p < end && (std::isspace(static_cast<unsigned char>(*p)) || *p == ',')) ++p;
    if (p == end) return !out.empty();
    if (*p == '+') ++p;  // from_chars takes no '+'; OpenCV never writes one, people might
    double v = 0;
    const auto r = std::from_chars(p, end, v);
    if (r.ec != std::errc() || r.ptr == p) return false;
    if (r.ptr < end && !std::isspace(static_cast<unsigned char>(*r.ptr)) && *r.ptr != ',') return false;
    out.push_back(v);
    p = r.ptr;
  }
}

std::string xmlEscape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

CvStorage parseOpenCvXml(const std::string& text, const std::string& name) {
  const XmlElement root = XmlParser(text, name).parseDocument();
  if (root.name != "opencv_storage")
    throw Error(oneLine(name + ": not an OpenCV FileStorage XML file (the root element is <" + root.name +
                        ">, expected <opencv_storage>)"));
  CvStorage storage;
  for (const XmlElement& e : root.children)
    if (!storage.count(e.name)) storage[e.name] = entryValue(e, name);  // the first of repeated keys
  return storage;
}

}  // namespace cs::calib
