#pragma once

// Helpers shared by the libFuzzer targets of the file readers (tests/fuzz/*_fuzzer.cc).
//
// The readers take file paths, so each input is written to a file of the right name in a
// per-process scratch folder (/dev/shm, else $TMPDIR, else /tmp), which is removed at exit.
// imumatch::Error (InputError, InvalidArgument, OutOfRange) is the expected outcome of bad input;
// any other exception escapes LLVMFuzzerTestOneInput and libFuzzer reports it as a crash
// (std::terminate -> abort).

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>
#include <utility>

#include "imumatch/core/error.h"

namespace imumatch::fuzz {

namespace fs = std::filesystem;

inline void RemoveScratchDir();

// The per-process scratch folder, created on first use and removed at normal exit. Never
// destroyed itself, so that the atexit handler can still use it.
inline const fs::path& ScratchDir() {
  static const fs::path* const dir = [] {
    fs::path base = "/dev/shm";
    std::error_code ec;
    if (!fs::is_directory(base, ec) || ::access(base.c_str(), W_OK) != 0) {
      const char* tmp = std::getenv("TMPDIR");
      base = tmp != nullptr && *tmp != '\0' ? fs::path(tmp) : fs::path("/tmp");
    }
    auto* d = new fs::path(base / ("imumatch_fuzz_" + std::to_string(::getpid())));
    fs::remove_all(*d, ec);
    fs::create_directories(*d);
    std::atexit(RemoveScratchDir);
    return d;
  }();
  return *dir;
}

inline void RemoveScratchDir() {
  std::error_code ec;
  fs::remove_all(ScratchDir(), ec);
}

// A fresh, empty sub-folder of the scratch folder (the same path on every call with that name).
inline std::string FreshDir(const std::string& name) {
  const fs::path d = ScratchDir() / name;
  std::error_code ec;
  fs::remove_all(d, ec);
  fs::create_directories(d);
  return d.string();
}

// Writes bytes to dir/relative (creating sub-folders) and returns the path.
inline std::string WriteFile(const std::string& dir, const std::string& relative, const void* data,
                             size_t size) {
  const fs::path p = fs::path(dir) / relative;
  fs::create_directories(p.parent_path());
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
  out.close();
  if (!out) std::abort();  // the harness itself failed: not a finding about the input
  return p.string();
}

inline std::string WriteFile(const std::string& dir, const std::string& relative,
                             const std::string& text) {
  return WriteFile(dir, relative, text.data(), text.size());
}

// Writes the fuzz input to a fresh folder <target> as file `relative`; returns its path.
inline std::string WriteInput(const std::string& target, const std::string& relative,
                              const uint8_t* data, size_t size) {
  return WriteFile(FreshDir(target), relative, data, size);
}

// Runs fn; an imumatch::Error is the expected answer to bad input and is swallowed, anything
// else escapes to libFuzzer. Always returns 0 (libFuzzer's "keep going"). Environment:
//   IMUMATCH_FUZZ_VERBOSE=1  print the outcome (for reproducing one input);
//   IMUMATCH_FUZZ_STRICT=1   also abort on an imumatch::Error that is not an InputError naming a
//                            file (the readers' contract: bad data is InputError(file, ...)).
template <class Fn>
int Expect(Fn&& fn) {
  static const bool verbose = std::getenv("IMUMATCH_FUZZ_VERBOSE") != nullptr;
  static const bool strict = std::getenv("IMUMATCH_FUZZ_STRICT") != nullptr;
  try {
    std::forward<Fn>(fn)();
    if (verbose) std::fprintf(stderr, "imumatch fuzz: accepted\n");
  } catch (const InputError& e) {
    if (verbose) std::fprintf(stderr, "imumatch fuzz: rejected: %s\n", e.what());
    if (strict && e.file().empty()) {
      std::fprintf(stderr, "imumatch fuzz: STRICT: InputError names no file: %s\n", e.what());
      std::abort();
    }
  } catch (const Error& e) {
    if (verbose) std::fprintf(stderr, "imumatch fuzz: rejected (not InputError): %s\n", e.what());
    if (strict) {
      std::fprintf(stderr, "imumatch fuzz: STRICT: not an InputError: %s\n", e.what());
      std::abort();
    }
  }
  return 0;
}

// Runs a follow-up query on what a reader returned (e.g. an IMU interpolation, which may
// legitimately throw OutOfRange over a gap): every imumatch::Error is accepted, even when strict.
template <class Fn>
void Query(Fn&& fn) {
  try {
    std::forward<Fn>(fn)();
  } catch (const Error&) {
  }
}

// Inputs of the multi-file targets: "<file name>\n<content>". The first line names the file of
// the folder that the rest replaces; it must be one of `names`, else the input is ignored (an
// empty name is not a file). Returns the index in `names` (-1 when none) and the content.
inline std::pair<int, std::string> SplitNamedInput(const uint8_t* data, size_t size,
                                                   std::initializer_list<const char*> names) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const size_t nl = text.find('\n');
  if (nl == std::string::npos) return {-1, ""};
  const std::string name = text.substr(0, nl);
  int i = 0;
  for (const char* n : names) {
    if (name == n) return {i, text.substr(nl + 1)};
    ++i;
  }
  return {-1, ""};
}

}  // namespace imumatch::fuzz
