// Runs the volley command for the CLI tests and captures its output and exit status.
#pragma once
#include <doctest/doctest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <regex>
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

/// A scratch folder of the CLI tests, and files in it.
inline std::filesystem::path temp_path(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "volley_trace_test";
  std::filesystem::create_directories(dir);
  return dir / name;
}

inline std::filesystem::path temp_file(const std::string& name, const std::string& content) {
  const std::filesystem::path p = temp_path(name);
  std::ofstream(p, std::ios::binary) << content;
  return p;
}

inline std::string bytes_of(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

/// The Cornell box scene of scenes/: the CLI tests' usual scene.
inline const std::string kCornell = std::string(VOLLEY_SOURCE_DIR) + "/scenes/cornell.json";

inline bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

/// The parsed `NAME: key=value ...` line (trace, query).
inline std::map<std::string, std::string> trace_line(const std::string& output, const std::string& name = "trace") {
  std::map<std::string, std::string> kv;
  const std::regex line("^" + name + ": (.*)$", std::regex::multiline);
  std::smatch m;
  if (!std::regex_search(output, m, line)) return kv;
  const std::string fields = m[1];
  const std::regex pair(R"((\S+)=(\S+))");
  for (auto it = std::sregex_iterator(fields.begin(), fields.end(), pair); it != std::sregex_iterator(); ++it)
    kv[(*it)[1]] = (*it)[2];
  return kv;
}

}  // namespace volley::test
