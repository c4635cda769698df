// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <stdexcept>
#include <string>

namespace gcpstereo {

// The one error type of the project. Bad input, bad configuration and failed I/O throw an Error
// (or a subclass) whose message names the file, key or value at fault. Expected numerical outcomes
// (a tile without GCPs, a solver that did not converge) are reported in result structs instead.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

// A file could not be read or written, or its content is malformed. The message starts with the
// path.
class IoError : public Error {
 public:
  IoError(const std::string& path, const std::string& problem)
      : Error(path + ": " + problem), path_(path) {}
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// A configuration key is unknown, of the wrong type or out of range.
class ConfigError : public Error {
 public:
  using Error::Error;
};

// A number as it appears in messages: the default stream form ("0.5", "1e-08", "inf").
std::string FormatNumber(double value);

// Formats "name = value. Violated constraint: constraint" in the style of Ceres' option checks.
std::string ViolatedConstraint(const std::string& name, const std::string& value,
                               const std::string& constraint);

}  // namespace gcpstereo
