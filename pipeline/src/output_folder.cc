// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/pipeline/output_folder.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "gcpstereo/core/error.h"
#include "gcpstereo/io/atomic_file.h"

namespace fs = std::filesystem;

namespace gcpstereo::pipeline {

OutputFolder::OutputFolder(const std::string& final_dir) : final_dir_(final_dir) {
  // "" is no folder (std::filesystem says "Invalid argument", and relative names would land in the
  // working folder); the command line names its option for it before getting here.
  if (final_dir.empty()) throw Error("the output folder path is empty");
  std::error_code ec;
  if (fs::exists(final_dir, ec) && !fs::is_directory(final_dir, ec)) {
    throw IoError(final_dir, "output path exists and is not a folder");
  }
  fs::create_directories(final_dir, ec);
  if (ec) throw IoError(final_dir, "cannot create output folder: " + ec.message());
  // Staging folders of runs that were killed (a signal runs no destructor) are removed: their
  // process is gone.
  for (const auto& entry : fs::directory_iterator(final_dir, ec)) {
    const std::string name = entry.path().filename().string();
    const std::string prefix = ".gcpstereo-staging-";
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string pid_text = name.substr(prefix.size());
    if (pid_text.empty() ||
        !std::all_of(pid_text.begin(), pid_text.end(), [](char c) { return c >= '0' && c <= '9'; }))
      continue;
    const long pid = std::strtol(pid_text.c_str(), nullptr, 10);
    std::error_code ignored;
    if (pid > 0 && kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH) {
      fs::remove_all(entry.path(), ignored);
    }
  }
  staging_dir_ =
      (fs::path(final_dir) / (".gcpstereo-staging-" + std::to_string(getpid()))).string();
  fs::remove_all(staging_dir_, ec);
  fs::create_directory(staging_dir_, ec);
  if (ec) throw IoError(staging_dir_, "cannot create staging folder: " + ec.message());
}

OutputFolder::~OutputFolder() {
  std::error_code ec;
  if (!staging_dir_.empty()) fs::remove_all(staging_dir_, ec);
}

std::string OutputFolder::Path(const std::string& name) {
  if (std::find(names_.begin(), names_.end(), name) == names_.end()) names_.push_back(name);
  return (fs::path(staging_dir_) / name).string();
}

std::string OutputFolder::FinalPath(const std::string& name) const {
  return (fs::path(final_dir_) / name).string();
}

void OutputFolder::Commit() {
  // The files the previous run in this folder committed (its manifest): those this run does not
  // write again are removed, so the folder never mixes two runs' outputs. Other files are kept.
  const fs::path manifest = fs::path(final_dir_) / kManifestName;
  std::vector<std::string> previous;
  {
    std::ifstream in(manifest);
    for (std::string line; std::getline(in, line);) {
      if (!line.empty() && line.find('/') == std::string::npos && line != "." && line != "..") {
        previous.push_back(line);
      }
    }
  }
  std::vector<std::string> written;
  for (const auto& name : names_) {
    std::error_code ec;
    if (fs::exists(fs::path(staging_dir_) / name, ec)) written.push_back(name);
  }
  for (const auto& name : previous) {
    if (std::find(written.begin(), written.end(), name) != written.end()) continue;
    std::error_code ec;
    const fs::path stale = fs::path(final_dir_) / name;
    // A folder (colmap/) goes whole: it was staged and committed as one output.
    const fs::file_status status = fs::symlink_status(stale, ec);
    if (fs::is_regular_file(status)) {
      fs::remove(stale, ec);
    } else if (fs::is_directory(status)) {
      fs::remove_all(stale, ec);
    }
  }
  // Each file moves by one rename: a run killed during these few milliseconds leaves every file
  // whole, the previous run's or this one's. The previous effective_config.yaml goes first and
  // the new one moves last, after report.json: a scene run reuses a view folder only when both
  // are there and the configuration is its own (scene.cc, ViewFolderComplete), so a commit cut
  // short is never taken for a finished view, of either configuration.
  if (std::find(written.begin(), written.end(), "effective_config.yaml") != written.end()) {
    std::error_code ec;
    fs::remove(fs::path(final_dir_) / "effective_config.yaml", ec);
  }
  std::vector<std::string> order = names_;
  std::stable_partition(order.begin(), order.end(), [](const std::string& name) {
    return name != "report.json" && name != "effective_config.yaml";
  });
  std::stable_partition(order.begin(), order.end(),
                        [](const std::string& name) { return name != "effective_config.yaml"; });
  for (const auto& name : order) {
    const fs::path from = fs::path(staging_dir_) / name;
    std::error_code ec;
    if (!fs::exists(from, ec)) continue;  // a file that was planned but not written
    const fs::path to = fs::path(final_dir_) / name;
    if (fs::is_directory(to, ec)) fs::remove_all(to, ec);
    fs::rename(from, to, ec);
    if (ec) throw IoError(to.string(), "cannot move output into place: " + ec.message());
  }
  std::string text;
  for (const auto& name : written) text += name + "\n";
  io::WriteBytesAtomically(manifest.string(), text.data(), text.size());
  committed_ = true;
}

}  // namespace gcpstereo::pipeline
