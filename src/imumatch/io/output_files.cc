#include "imumatch/io/output_files.h"

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "imumatch/core/error.h"

namespace imumatch {
namespace {

namespace fs = std::filesystem;

std::set<std::string> ReadManifest(const fs::path& dir) {
  std::set<std::string> names;
  std::ifstream in(dir / kOutputManifest);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty()) names.insert(line);
  }
  return names;
}

}  // namespace

void WriteFileAtomic(const std::string& path, const std::string& bytes) {
  const fs::path target(path);
  const fs::path tmp = target.parent_path() / ("." + target.filename().string() + ".tmp-" +
                                               std::to_string(static_cast<long>(::getpid())));
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw Error("cannot write " + path + " (cannot create " + tmp.string() + ")");
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out) {
      std::error_code ec;
      fs::remove(tmp, ec);
      throw Error("error while writing " + path);
    }
  }
  std::error_code ec;
  fs::rename(tmp, target, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw Error("cannot write " + path + ": " + ec.message());
  }
}

OutputFolderCheck PrepareOutputFolder(const std::string& dir, bool overwrite) {
  OutputFolderCheck check;
  const fs::path p(dir);
  std::error_code ec;
  if (fs::exists(p, ec) && !fs::is_directory(p, ec)) {
    throw InvalidArgument("output folder " + dir + " is a file, not a folder");
  }
  if (!fs::exists(p, ec)) {
    fs::create_directories(p, ec);
    if (ec) throw InvalidArgument("cannot create output folder " + dir + ": " + ec.message());
    check.created = true;
  }
  // Writable? (A read-only mount, missing permissions: said now, not after the work.)
  const fs::path probe =
      p / (".imumatch-write-test-" + std::to_string(static_cast<long>(::getpid())));
  {
    std::ofstream out(probe);
    if (!out) throw InvalidArgument("output folder " + dir + " is not writable");
  }
  fs::remove(probe, ec);
  if (check.created) return check;
  const std::set<std::string> manifest = ReadManifest(p);
  std::vector<std::string> foreign;
  for (const fs::directory_entry& e : fs::directory_iterator(p, ec)) {
    const std::string name = e.path().filename().string();
    if (name == kOutputManifest) continue;
    if (manifest.count(name)) {
      check.earlier.push_back(name);
    } else {
      foreign.push_back(name);
    }
  }
  std::sort(foreign.begin(), foreign.end());
  if (!foreign.empty() && !overwrite) {
    std::ostringstream msg;
    msg << "output folder " << dir << " holds " << foreign.size()
        << " file(s) imumatch did not write (e.g. '" << foreign.front()
        << "'); choose another --out or pass --overwrite";
    throw InvalidArgument(msg.str());
  }
  if (!check.earlier.empty() || !foreign.empty()) {
    std::ostringstream note;
    note << "writing into " << dir << ": replacing the outputs of an earlier run";
    if (!foreign.empty()) note << " (--overwrite: " << foreign.size() << " other file(s) kept)";
    check.note = note.str();
  }
  return check;
}

void RecordOutputs(const std::string& dir, const std::vector<std::string>& written) {
  const fs::path p(dir);
  std::set<std::string> names = ReadManifest(p);
  for (const std::string& w : written) {
    const fs::path rel = fs::path(w).lexically_relative(p);
    if (!rel.empty() && rel.begin() != rel.end()) names.insert(rel.begin()->string());
  }
  std::string text;
  for (const std::string& n : names) text += n + "\n";
  WriteFileAtomic((p / kOutputManifest).string(), text);
}

}  // namespace imumatch
