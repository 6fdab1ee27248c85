#pragma once
// Test support: runs the real `svbtdf` binary and captures its output and exit status.
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace svbtdf::testing {

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr, interleaved
};

// Runs `svbtdf <arguments>` through the shell (arguments are not quoted for you), with
// `environment` (e.g. "SVBTDF_INJECT_FAULT=3:kill") set for it alone.
inline CommandResult RunSvbtdf(const std::string& arguments, const std::string& environment = "") {
  const std::string command = environment + " " + std::string(SVBTDF_CLI_PATH) + " " + arguments + " 2>&1";
  CommandResult result;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) return result;
  std::array<char, 4096> buffer;
  size_t n;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0) result.output.append(buffer.data(), n);
  const int status = ::pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

}  // namespace svbtdf::testing
