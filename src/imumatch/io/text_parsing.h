#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace imumatch {

// Low-level helpers shared by the io readers: every error is an InputError naming file and line.

// One non-empty, non-comment line of a text file split into fields.
struct TextLine {
  int line = 0;  // 1-based line number in the file
  std::vector<std::string> fields;
};

enum class FieldSeparator {
  kWhitespace,  // TUM style: "t tx ty tz ..."
  kComma,       // CSV (EuRoC): "t,wx,wy,..."; spaces around fields are ignored
};

// Reads a text file into lines of fields. Blank lines and lines whose first non-blank character is
// '#' are skipped; a trailing '\r' (Windows line end) is ignored. Throws InputError(path, ...) when
// the file is missing or unreadable, and InputError(path, line, ...) for an empty CSV field.
std::vector<TextLine> ReadTextFields(const std::string& path, FieldSeparator separator);
// Same on text already in memory; source_name is used in the errors.
std::vector<TextLine> SplitTextFields(const std::string& text, const std::string& source_name,
                                      FieldSeparator separator);

// Reads a whole file into a string. Throws InputError(path, ...) when it cannot be opened.
std::string ReadFileToString(const std::string& path);

// Throws InputError(file, line, "expected N fields (format), got M") unless the count matches.
void CheckFieldCount(const TextLine& line, size_t expected, const std::string& file,
                     const std::string& format);

// A finite double, or InputError(file, line, "<what>: 'x' is not a number" / "is not finite").
double ParseFiniteDouble(const std::string& token, const std::string& file, int line,
                         const std::string& what);
// Decimal seconds -> ns (exact, see ParseSecondsToNs) or integer ns, with InputError on bad text.
int64_t ParseSecondsField(const std::string& token, const std::string& file, int line);
int64_t ParseNsField(const std::string& token, const std::string& file, int line);

// Throws InputError(file, line, ...) unless t_ns is strictly after previous_t_ns (names a duplicate
// or an out-of-order timestamp). Does nothing when previous_line == 0 (first record).
void CheckIncreasingTimestamp(int64_t previous_t_ns, int previous_line, int64_t t_ns,
                              const std::string& file, int line);

// A unit quaternion from four parsed numbers: normalised when |norm - 1| <= tolerance, otherwise
// InputError(file, line, "quaternion norm ... is not 1").
Eigen::Quaterniond CheckedUnitQuaternion(double w, double x, double y, double z,
                                         const std::string& file, int line,
                                         double tolerance = 1e-3);

// Decimal text that reads back to exactly the same double ("%.17g").
std::string FormatDoubleExact(double value);

}  // namespace imumatch
