// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "test_data.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>
#include <random>
#include <vector>

namespace fs = std::filesystem;

namespace gcpstereo::testing {
namespace {

struct TempDirs {
  std::vector<fs::path> dirs;
  std::mutex mutex;
  ~TempDirs() {
    std::error_code ec;
    for (const auto& d : dirs) fs::remove_all(d, ec);
  }
};
TempDirs& Temps() {
  static TempDirs temps;
  return temps;
}

}  // namespace

std::string SharedDataDir() {
  const char* env = std::getenv("GCPSTEREO_DATA");
  const fs::path dir = (env && *env) ? fs::path(env) : fs::path(GCPSTEREO_DEFAULT_DATA_DIR);
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return "";
  return fs::canonical(dir, ec).string();
}

std::string SharedDataPath(const std::string& relative) {
  const std::string dir = SharedDataDir();
  if (dir.empty()) return "";
  const fs::path p = fs::path(dir) / relative;
  std::error_code ec;
  return fs::exists(p, ec) ? p.string() : "";
}

std::string MakeTempDir(const std::string& prefix) {
  std::random_device rd;
  std::lock_guard<std::mutex> lock(Temps().mutex);
  for (int attempt = 0; attempt < 100; ++attempt) {
    const fs::path p = fs::temp_directory_path() / (prefix + "-" + std::to_string(rd()));
    std::error_code ec;
    if (fs::create_directory(p, ec)) {
      Temps().dirs.push_back(p);
      return p.string();
    }
  }
  throw std::runtime_error("cannot create a temporary directory");
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

}  // namespace gcpstereo::testing
