// Runs the volley command for the CLI tests and captures its output and exit status.
#pragma once
#include <doctest/doctest.h>

#include <array>
#include <cstdio>
#include <string>

#include <sys/wait.h>

namespace volley::test {

struct Run {
  int status;
  std::string output;  // stdout and stderr together
};

/// Runs `volley ARGS` (the binary under test) through the shell.
inline Run run(const std::string& args) {
  const std::string cmd = std::string(VOLLEY_BINARY) + " " + args + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  REQUIRE(pipe != nullptr);
  std::string out;
  std::array<char, 4096> buf;
  while (std::size_t n = std::fread(buf.data(), 1, buf.size(), pipe)) out.append(buf.data(), n);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status), out};
}

}  // namespace volley::test
