// imumatch: IMU-guided feature matching between consecutive camera frames.
//
// Exit codes: 0 success, 1 runtime error, 2 usage error, 3 bad input data (file:line named),
// 4 invalid option value.
#include <exception>
#include <iostream>

#include <CLI/CLI.hpp>

#include "commands.h"
#include "imumatch/core/error.h"

int main(int argc, char** argv) {
  CLI::App app{
      "imumatch: predict where features move from the IMU, then match only there.\n"
      "Run 'imumatch demo' for the built-in synthetic comparison."};
  app.set_version_flag("--version", std::string("imumatch 0.1.0"));
  app.require_subcommand(1);
  // Subcommands register themselves here.
  imumatch::apps::AddSynthCommand(app);
  imumatch::apps::AddImuCommand(app);
  imumatch::apps::AddDemoCommand(app);
  imumatch::apps::AddEvalCommand(app);
  imumatch::apps::AddTrackCommand(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version are "errors" with code 0; everything else is a usage error (2).
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  } catch (const imumatch::InputError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 3;
  } catch (const imumatch::InvalidArgument& e) {
    std::cerr << "error: invalid argument: " << e.what() << "\n";
    return 4;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
