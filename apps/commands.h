#pragma once

#include <CLI/CLI.hpp>

namespace imumatch::apps {

// Each subcommand adds itself to the app; the callback runs the command and may throw any
// imumatch::Error, which main() maps to an exit code.
// (Declared here, defined in <name>_command.cc, called from main.cc.)
void AddSynthCommand(CLI::App& app);  // synth_command.cc
void AddImuCommand(CLI::App& app);    // imu_command.cc
void AddEvalCommand(CLI::App& app);   // eval_command.cc
void AddDemoCommand(CLI::App& app);   // eval_command.cc
void AddTrackCommand(CLI::App& app);  // track_command.cc

}  // namespace imumatch::apps
