#pragma once

#include <string>
#include <vector>

#include "imumatch/core/types.h"
#include "imumatch/imu/imu_buffer.h"
#include "imumatch/io/text_parsing.h"

namespace imumatch {

// Plain-text IMU logs (our synthetic sequences' imu.txt): one sample a line,
//   t_s gx gy gz ax ay az
// seconds (decimal, exact to the ns), rad/s, m/s^2 (specific force, gravity included); '#' starts
// a comment line.

// Throws InputError(path, line, ...) for a missing file, wrong field count, non-numeric or
// non-finite value, and (through ImuBuffer::Push) duplicate or out-of-order timestamps.
ImuBuffer ReadImuText(const std::string& path, const ImuBufferOptions& options = {});

// The table reader behind ReadImuText and ReadEurocImu (euroc.h): seven fields a line, a timestamp
// (decimal seconds or integer nanoseconds) then gyro x y z and accelerometer x y z. `layout`
// describes the fields in errors, `names` labels the six values. Throws like ReadImuText, and
// InputError when the file holds no sample.
enum class ImuTimeUnit { kSeconds, kNanoseconds };
ImuBuffer ReadImuTable(const std::string& path, FieldSeparator separator, ImuTimeUnit time_unit,
                       const std::string& layout, const char* const (&names)[6],
                       const ImuBufferOptions& options);

// Writes samples so that ReadImuText returns them bit for bit (9-decimal seconds, 17-digit
// values). Throws Error when the file cannot be written.
void WriteImuText(const std::string& path, const std::vector<ImuSample>& samples,
                  const std::string& header_comment = "");

}  // namespace imumatch
