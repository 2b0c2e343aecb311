// jpcr_eval: error metrics of trajectories (TUM conventions) and curvature maps, and noise
// studies of the pair refiners.
#include <cstring>
#include <iostream>
#include <string>

#include "cli/arguments.hpp"
#include "jpcr_eval/eval_commands.hpp"

namespace {

constexpr const char* kUsage =
    "usage: jpcr_eval COMMAND [options]\n\n"
    "Evaluates jpcr results against ground truth, and studies the refiners under noise.\n\n"
    "commands:\n"
    "  traj        trajectory error: ATE, RPE per frame and per second, paper-style relative\n"
    "              errors and drift (jpcr_eval traj --gt GT.txt --est EST.txt [--json]);\n"
    "              --baseline B.txt: better, worse or indistinguishable from B\n"
    "  curvature   principal-curvature RMS error and coverage against jpcr_synth ground truth\n"
    "              (jpcr_eval curvature --gt DIR --est DIR [--json])\n"
    "  noise       Monte-Carlo study of J-ftf / Q-full / ICP-ftf on a synthetic frame pair:\n"
    "              bias, spread and predicted spread over noise draws\n"
    "              (jpcr_eval noise --noise range:3)\n\n"
    "Run 'jpcr_eval COMMAND --help' for the options of a command.\n";

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
    std::cout << kUsage;
    return argc < 2 ? 2 : 0;
  }
  const std::string command = argv[1];
  if (command == "traj") return jpcr::eval::run_trajectory(argc - 1, argv + 1);
  if (command == "curvature") return jpcr::eval::run_curvature(argc - 1, argv + 1);
  if (command == "noise") return jpcr::eval::run_noise(argc - 1, argv + 1);
  std::cerr << "jpcr_eval: unknown command '" << command << "'\n" << kUsage;
  return 2;
}
