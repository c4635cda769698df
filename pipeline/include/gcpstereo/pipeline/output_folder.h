// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <string>
#include <vector>

namespace gcpstereo::pipeline {

// The output folder of a run. Files are written into a hidden staging folder inside it and moved
// to their final names only by Commit(), so a run that fails leaves no partial output under a
// final name (../shared/CONTRACT.md); the staging folder is removed unless committed, and staging
// folders of killed runs are removed by the next run into the same folder.
class OutputFolder {
 public:
  // Creates `final_dir` (and parents) if needed; throws IoError when that is impossible or when
  // `final_dir` exists and is not a folder, and Error when `final_dir` is empty.
  explicit OutputFolder(const std::string& final_dir);
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  // Where to write the output file `name` now (inside the staging folder). `name` may also be a
  // folder the caller creates there and fills (colmap/): it is committed, and replaced, whole.
  std::string Path(const std::string& name);
  // Where `name` will be after Commit().
  std::string FinalPath(const std::string& name) const;
  const std::string& final_dir() const { return final_dir_; }

  // Moves every file written into the staging folder to its final name (replacing older files of
  // the same name) and removes the staging folder. The names committed are listed in the folder's
  // kManifestName; files the previous run listed there and this run did not write are removed
  // first (files, and folders whole), so a folder reused with other options holds one run's
  // outputs (other files are kept).
  void Commit();

  static constexpr const char* kManifestName = ".gcpstereo-outputs";

 private:
  std::string final_dir_;
  std::string staging_dir_;
  std::vector<std::string> names_;
  bool committed_ = false;
};

}  // namespace gcpstereo::pipeline
