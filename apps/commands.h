#pragma once

#include <cstddef>
#include <functional>
#include <sstream>
#include <string>

#include <CLI/CLI.hpp>

#include "imumatch/core/error.h"

namespace imumatch::apps {

// Each subcommand adds itself to the app; the callback runs the command and may throw any
// imumatch::Error, which main() maps to an exit code.
// (Declared here, defined in <name>_command.cc, called from main.cc.)
void AddSynthCommand(CLI::App& app);  // synth_command.cc
void AddImuCommand(CLI::App& app);    // imu_command.cc
void AddEvalCommand(CLI::App& app);   // eval_command.cc
void AddDemoCommand(CLI::App& app);   // eval_command.cc
void AddTrackCommand(CLI::App& app);  // track_command.cc

// --camera FILE of eval and track: the dataset's intrinsics and lens replaced (ReadCameraFile).
inline constexpr const char* kCameraOptionHelp =
    "replace the dataset's intrinsics and lens: a Kalibr/EuRoC camera sensor.yaml (*.yaml; its "
    "extrinsics are not used) or a text line as camera.txt ('[radtan|equidistant] fx fy cx cy "
    "width height k...'); the images must have its size";

inline constexpr const char* kTimeshiftOptionHelp =
    "EuRoC/ASL: the camera's clock offset from the IMU's (s, t_imu = t_cam + shift), replacing "
    "the calibration's timeshift_cam_imu; eval and track measure what is left of it from the "
    "fitted rotations and say when it is worth setting";

// --threads N (0 = all cores): OpenCV's worker threads (feature extraction, image decoding) via
// cv::setNumThreads; returns the count used. eval_command.cc.
int ApplyThreads(int threads);

// A one-line progress bar on stderr when forced or when stderr is a TTY (and total >= 10):
// "<label> [###...] done/total <unit>, elapsed, eta". nullptr when off. eval_command.cc.
std::function<void(size_t, size_t)> MakeProgress(bool forced, size_t total,
                                                 const std::string& label,
                                                 const std::string& unit = "pairs");

}  // namespace imumatch::apps
