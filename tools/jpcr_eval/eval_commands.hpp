// Subcommands of jpcr_eval. Each parses its own arguments (argv[0] is the subcommand name).
#pragma once

namespace jpcr::eval {

int run_trajectory(int argc, char** argv);
int run_curvature(int argc, char** argv);
int run_noise(int argc, char** argv);

}  // namespace jpcr::eval
