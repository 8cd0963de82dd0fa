#include "imumatch/io/text_parsing.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "imumatch/core/error.h"
#include "imumatch/core/time.h"
#include "imumatch/io/plausibility.h"

namespace imumatch {
namespace {

std::string Trim(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  const size_t e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

std::string Shorten(const std::string& token) {
  return token.size() <= 40 ? token : token.substr(0, 37) + "...";
}

}  // namespace

std::string ReadFileToString(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path, "file not found");
  if (std::filesystem::is_directory(path, ec)) throw InputError(path, "is a folder, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open file for reading");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw InputError(path, "read error");
  return buffer.str();
}

std::vector<TextLine> SplitTextFields(const std::string& text, const std::string& source_name,
                                      FieldSeparator separator) {
  std::vector<TextLine> lines;
  // A UTF-8 byte-order mark (written by some Windows editors) is not part of the first field.
  size_t pos = text.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0;
  int line_no = 0;
  while (pos < text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    ++line_no;
    const std::string line = Trim(text.substr(pos, end - pos));
    pos = end + 1;
    if (line.empty() || line[0] == '#') continue;
    TextLine out;
    out.line = line_no;
    if (separator == FieldSeparator::kWhitespace) {
      std::istringstream fields(line);
      std::string token;
      while (fields >> token) out.fields.push_back(token);
    } else {
      size_t start = 0;
      while (true) {
        const size_t comma = line.find(',', start);
        const std::string field = Trim(
            line.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
        if (field.empty()) {
          throw InputError(source_name, line_no,
                           "empty field " + std::to_string(out.fields.size() + 1) + " in CSV line");
        }
        out.fields.push_back(field);
        if (comma == std::string::npos) break;
        start = comma + 1;
      }
    }
    lines.push_back(std::move(out));
  }
  return lines;
}

std::vector<TextLine> ReadTextFields(const std::string& path, FieldSeparator separator) {
  return SplitTextFields(ReadFileToString(path), path, separator);
}

void CheckFieldCount(const TextLine& line, size_t expected, const std::string& file,
                     const std::string& format) {
  if (line.fields.size() != expected) {
    throw InputError(file, line.line,
                     "expected " + std::to_string(expected) + " fields (" + format + "), got " +
                         std::to_string(line.fields.size()));
  }
}

double ParseFiniteDouble(const std::string& token, const std::string& file, int line,
                         const std::string& what) {
  const char* begin = token.c_str();
  char* end = nullptr;
  const double v = std::strtod(begin, &end);
  if (token.empty() || end != begin + token.size()) {
    throw InputError(file, line, what + ": '" + Shorten(token) + "' is not a number");
  }
  // Overflow gives +-inf (rejected here); underflow gives a tiny or zero value (accepted).
  if (!std::isfinite(v)) {
    throw InputError(file, line, what + ": '" + Shorten(token) + "' is not finite");
  }
  return v;
}

int64_t ParseSecondsField(const std::string& token, const std::string& file, int line) {
  int64_t t_ns = 0;
  try {
    t_ns = ParseSecondsToNs(token);
  } catch (const InvalidArgument&) {
    throw InputError(file, line,
                     "timestamp '" + Shorten(token) + "' is not a finite number of seconds");
  }
  plausibility::CheckTimestamp(t_ns, file, line);
  return t_ns;
}

int64_t ParseNsField(const std::string& token, const std::string& file, int line) {
  int64_t t_ns = 0;
  try {
    t_ns = ParseNs(token);
  } catch (const InvalidArgument&) {
    throw InputError(file, line,
                     "timestamp '" + Shorten(token) + "' is not an integer number of nanoseconds");
  }
  plausibility::CheckTimestamp(t_ns, file, line);
  return t_ns;
}

void CheckIncreasingTimestamp(int64_t previous_t_ns, int previous_line, int64_t t_ns,
                              const std::string& file, int line) {
  if (previous_line == 0) return;
  if (t_ns == previous_t_ns) {
    throw InputError(file, line,
                     "duplicate timestamp " + FormatNsAsSeconds(t_ns) + " s (same as line " +
                         std::to_string(previous_line) + ")");
  }
  if (t_ns < previous_t_ns) {
    throw InputError(file, line,
                     "timestamp " + FormatNsAsSeconds(t_ns) + " s is before the previous one (" +
                         FormatNsAsSeconds(previous_t_ns) + " s on line " +
                         std::to_string(previous_line) + "): timestamps must increase");
  }
  plausibility::CheckTimestampStep(previous_t_ns, previous_line, t_ns, file, line);
}

Eigen::Quaterniond CheckedUnitQuaternion(double w, double x, double y, double z,
                                         const std::string& file, int line, double tolerance) {
  Eigen::Quaterniond q(w, x, y, z);
  const double norm = q.norm();
  if (!(std::abs(norm - 1.0) <= tolerance)) {
    std::ostringstream msg;
    msg << "quaternion (w x y z = " << w << " " << x << " " << y << " " << z << ") has norm "
        << norm << ", not 1 (tolerance " << tolerance << ")";
    throw InputError(file, line, msg.str());
  }
  q.coeffs() /= norm;
  return q;
}

std::string FormatDoubleExact(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  return buffer;
}

}  // namespace imumatch
