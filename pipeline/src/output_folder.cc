// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/pipeline/output_folder.h"

#include <unistd.h>

#include <algorithm>
#include <filesystem>

#include "gcpstereo/core/error.h"

namespace fs = std::filesystem;

namespace gcpstereo::pipeline {

OutputFolder::OutputFolder(const std::string& final_dir) : final_dir_(final_dir) {
  std::error_code ec;
  if (fs::exists(final_dir, ec) && !fs::is_directory(final_dir, ec)) {
    throw IoError(final_dir, "output path exists and is not a folder");
  }
  fs::create_directories(final_dir, ec);
  if (ec) throw IoError(final_dir, "cannot create output folder: " + ec.message());
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
  for (const auto& name : names_) {
    const fs::path from = fs::path(staging_dir_) / name;
    std::error_code ec;
    if (!fs::exists(from, ec)) continue;  // a file that was planned but not written
    const fs::path to = fs::path(final_dir_) / name;
    if (fs::is_directory(to, ec)) fs::remove_all(to, ec);
    fs::rename(from, to, ec);
    if (ec) throw IoError(to.string(), "cannot move output into place: " + ec.message());
  }
  committed_ = true;
}

}  // namespace gcpstereo::pipeline
