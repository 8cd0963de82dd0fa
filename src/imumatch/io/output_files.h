#pragma once

#include <string>
#include <vector>

// Writing outputs safely: every file goes to a temporary name in its folder and is renamed over
// the target when complete, so an interrupted run never leaves half a file that looks whole, and
// a file that was hard-linked elsewhere is replaced, not rewritten in place. Output folders are
// checked before the work starts: writable, and holding no files the tool did not write unless
// the user says --overwrite.

namespace imumatch {

// Writes bytes to path atomically (temporary file + rename). Throws Error naming the path.
void WriteFileAtomic(const std::string& path, const std::string& bytes);

struct OutputFolderCheck {
  bool created = false;              // the folder did not exist
  std::vector<std::string> earlier;  // files of an earlier imumatch run that will be replaced
  std::string note;                  // one line for the user, empty when nothing to say
};

// The manifest an output folder keeps of the files imumatch wrote into it.
inline constexpr const char* kOutputManifest = ".imumatch-outputs";

// Before any work: creates dir if missing and checks that a file can be written there (throws
// InvalidArgument naming the folder and the reason otherwise). A folder that holds files other
// than those listed in its manifest (a dataset, a user's files) is refused with InvalidArgument
// unless overwrite is set; files of an earlier imumatch run are replaced, and `note` says so.
OutputFolderCheck PrepareOutputFolder(const std::string& dir, bool overwrite);

// After writing: records the files written (paths inside dir; added to the manifest's entries).
void RecordOutputs(const std::string& dir, const std::vector<std::string>& written);

}  // namespace imumatch
