// Runs a shell command line as a user would and keeps its exit status and
// its output (stdout and stderr together), for tests of the command-line
// tools.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace vpm::testing {

struct CommandRun {
  int exit_code;       // -1 when the command did not exit normally
  std::string output;  // stdout and stderr
};

inline CommandRun RunCommand(const std::string& command_line) {
  FILE* pipe = popen((command_line + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return {-1, "popen failed: " + command_line};
  std::string output;
  std::array<char, 4096> buffer;
  while (size_t n = fread(buffer.data(), 1, buffer.size(), pipe)) output.append(buffer.data(), n);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

}  // namespace vpm::testing
