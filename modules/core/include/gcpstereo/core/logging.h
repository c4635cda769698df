// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>
#include <utility>

#include <spdlog/spdlog.h>

namespace gcpstereo {

// Makes spdlog's default logger write trace … info messages to stdout and warnings and errors to
// stderr (so that a failing command's stderr holds just the problem), in colour on terminals.
void InstallConsoleLogger();

// The project logs through spdlog's default logger (GCP_LOG_INFO(...) etc. are spdlog::info(...)).
// Levels: "trace", "debug", "info", "warn", "error", "off".
void SetLogLevel(const std::string& level);

// Adds a file sink (the run's log in the output folder) next to the console sink. Throws IoError
// when the file cannot be opened.
void AddLogFile(const std::string& path);
// Removes file sinks added by AddLogFile (closing their files).
void RemoveLogFiles();
// Removes the file sink of `path` only (a scene's run.log stays while a view's closes).
void RemoveLogFile(const std::string& path);

// AddLogFile(path) for the lifetime of the object (a run's run.log).
class ScopedLogFile {
 public:
  explicit ScopedLogFile(std::string path) : path_(std::move(path)) { AddLogFile(path_); }
  ~ScopedLogFile() { RemoveLogFile(path_); }
  ScopedLogFile(const ScopedLogFile&) = delete;
  ScopedLogFile& operator=(const ScopedLogFile&) = delete;

 private:
  std::string path_;
};
// Writes `line` at error level to the log files only (whatever the log level): for an error the
// caller reports on stderr itself.
void LogToFilesOnly(const std::string& line);

}  // namespace gcpstereo
