#pragma once

#include <cstdlib>
#include <string>

namespace imumatch::testing {

// Folder of the shared real-data excerpts (../shared/data beside the checkout), overridable with
// the IMUMATCH_DATA_DIR environment variable. Tests that need it fail with a clear message when
// the folder is missing rather than skipping silently.
inline std::string DataDir() {
  if (const char* env = std::getenv("IMUMATCH_DATA_DIR"); env != nullptr && *env != '\0')
    return env;
  return IMUMATCH_TEST_DATA_DIR;
}

inline std::string DataPath(const std::string& relative) { return DataDir() + "/" + relative; }

}  // namespace imumatch::testing
