#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

namespace imumatch {

// Base class of every exception thrown by imumatch. Library code never calls exit() or abort():
// it throws, and the CLI maps exception types to exit codes.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A value given by the caller is out of range (options that fail Check(), bad arguments).
class InvalidArgument : public Error {
 public:
  using Error::Error;
};

// Input data is missing or malformed. The message names the file and, where known, the line:
// "path/to/file.txt:12: expected 7 numbers, got 6".
class InputError : public Error {
 public:
  InputError(const std::string& file, int line, const std::string& message)
      : Error(Format(file, line, message)), file_(file), line_(line) {}
  InputError(const std::string& file, const std::string& message)
      : Error(Format(file, 0, message)), file_(file), line_(0) {}

  const std::string& file() const { return file_; }
  int line() const { return line_; }  // 1-based; 0 when the error is not tied to a line.

 private:
  static std::string Format(const std::string& file, int line, const std::string& message) {
    std::ostringstream out;
    out << file;
    if (line > 0) out << ":" << line;
    out << ": " << message;
    return out.str();
  }
  std::string file_;
  int line_;
};

// A request the data cannot answer, e.g. an IMU query outside the buffered range or over a gap.
class OutOfRange : public Error {
 public:
  using Error::Error;
};

}  // namespace imumatch

// Throws imumatch::InvalidArgument(<message>) when cond is false; message is streamed
// (`"got " << x`). For checks whose message says all a user needs, as a command's checks of its
// own options, which name the option.
#define IMUMATCH_REQUIRE(cond, message)                                  \
  do {                                                                   \
    if (!(cond)) {                                                       \
      std::ostringstream imumatch_require_stream_;                       \
      imumatch_require_stream_ << message;                               \
      throw ::imumatch::InvalidArgument(imumatch_require_stream_.str()); \
    }                                                                    \
  } while (false)

// The same with the condition after the message, "<message> (required: <cond>)": the message
// first, as users read it (it names the value and says what is wrong), the condition for the
// caller who wrote the call.
#define IMUMATCH_CHECK(cond, message) IMUMATCH_REQUIRE(cond, message << " (required: " #cond ")")
