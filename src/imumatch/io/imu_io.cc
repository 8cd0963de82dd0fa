#include "imumatch/io/imu_io.h"

#include <fstream>
#include <sstream>

#include "imumatch/core/error.h"
#include "imumatch/core/time.h"
#include "imumatch/io/output_files.h"
#include "imumatch/io/plausibility.h"
#include "imumatch/io/text_parsing.h"

namespace imumatch {

ImuBuffer ReadImuTable(const std::string& path, FieldSeparator separator, ImuTimeUnit time_unit,
                       const std::string& layout, const char* const (&names)[6],
                       const ImuBufferOptions& options) {
  ImuBuffer buffer(options);
  int previous_line = 0;
  for (const TextLine& line : ReadTextFields(path, separator)) {
    CheckFieldCount(line, 7, path, layout);
    ImuSample s;
    s.t_ns = time_unit == ImuTimeUnit::kSeconds ? ParseSecondsField(line.fields[0], path, line.line)
                                                : ParseNsField(line.fields[0], path, line.line);
    double v[6];
    for (int i = 0; i < 6; ++i)
      v[i] = ParseFiniteDouble(line.fields[i + 1], path, line.line, names[i]);
    s.gyro_rad_s = Eigen::Vector3d(v[0], v[1], v[2]);
    s.accel_m_s2 = Eigen::Vector3d(v[3], v[4], v[5]);
    plausibility::CheckImu(s.gyro_rad_s, s.accel_m_s2, path, line.line);
    if (!buffer.empty()) {
      plausibility::CheckTimestampStep(buffer.samples().back().t_ns, previous_line, s.t_ns, path,
                                       line.line);
    }
    buffer.Push(s, path, line.line);
    previous_line = line.line;
  }
  if (buffer.empty()) throw InputError(path, "no IMU samples found");
  return buffer;
}

ImuBuffer ReadImuText(const std::string& path, const ImuBufferOptions& options) {
  static const char* const kNames[6] = {"gx", "gy", "gz", "ax", "ay", "az"};
  return ReadImuTable(path, FieldSeparator::kWhitespace, ImuTimeUnit::kSeconds,
                      "t_s gx gy gz ax ay az", kNames, options);
}

void WriteImuText(const std::string& path, const std::vector<ImuSample>& samples,
                  const std::string& header_comment) {
  std::ostringstream out;
  if (!header_comment.empty()) out << "# " << header_comment << "\n";
  out << "# t_s gx gy gz [rad/s] ax ay az [m/s^2]\n";
  for (const ImuSample& s : samples) {
    out << FormatNsAsSeconds(s.t_ns);
    for (int i = 0; i < 3; ++i) out << ' ' << FormatDoubleExact(s.gyro_rad_s[i]);
    for (int i = 0; i < 3; ++i) out << ' ' << FormatDoubleExact(s.accel_m_s2[i]);
    out << '\n';
  }
  WriteFileAtomic(path, out.str());
}

}  // namespace imumatch
