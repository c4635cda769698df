// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Runs the gcpstereo executable (GCPSTEREO_EXECUTABLE, defined for the pipeline tests) as a user
// would: cli_test.cpp and bad_input_test.cpp.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace gcpstereo::testing {

struct CliResult {
  int status = -1;
  std::string output;  // stdout and stderr, or stderr only
};

// Runs `args` through the shell (in the folder `working_dir` when given); captures stderr (and
// stdout when `with_stdout`).
inline CliResult RunCli(const std::string& args, bool with_stdout = false,
                        const std::string& working_dir = "") {
  const std::string command = (working_dir.empty() ? "" : "cd '" + working_dir + "' && ") +
                              std::string(GCPSTEREO_EXECUTABLE) + " " + args +
                              (with_stdout ? " 2>&1" : " 2>&1 >/dev/null");
  CliResult r;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buffer;
  size_t n;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0) r.output.append(buffer.data(), n);
  const int status = pclose(pipe);
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// Writes `text` to `path` and returns the path.
inline std::string WriteFile(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
  return path.string();
}

}  // namespace gcpstereo::testing
