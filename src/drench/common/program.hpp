#pragma once
/// Outside programs the drench command hands work to: ffmpeg for `drench render --video`, gnuplot for the
/// plot of `drench sweep`, xvfb-run in the tests. POSIX only, as the command is; the simulation never runs
/// one.

#include <string>
#include <vector>

namespace drench {

/// The full path of the program `name` on $PATH (the first executable file of that name, an empty entry
/// meaning the current folder), or "" when it is not there.
std::string find_program(const std::string& name);

/// Runs a program with this process's environment, standard output and error, and waits for it to end.
/// @param arguments  the program (a path, or a name looked up on $PATH) and its arguments; not empty
/// @return its exit status, 128 + the signal that ended it, or -1 when it could not be started or waited for
int run_program(const std::vector<std::string>& arguments);

}  // namespace drench
