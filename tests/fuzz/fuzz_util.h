// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Shared by the libFuzzer harnesses of tests/fuzz/ (built with -DGCPSTEREO_FUZZ=ON, run by
// tools/fuzz.sh). The readers take paths, so each harness writes its input to files in one
// temporary folder per process and calls the reader.
//
// What counts as a finding: a crash, a sanitizer report, a hang or an exception that is not a
// gcpstereo::Error (libFuzzer reports an escaping exception as a crash). A gcpstereo::Error is the
// expected refusal; RequireNamed() also checks that its message names the file at fault.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include <unistd.h>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/logging.h"

namespace gcpstereo::fuzz {

// Separates the files of a multi-file input (COLMAP's three files, KITTI's two calibration files):
// the seed corpora (tests/fuzz/make_corpus.py) hold it, and libFuzzer's mutations keep it.
inline constexpr std::string_view kSplit = "\n--gcpstereo-fuzz-file--\n";

// This process's scratch folder under $TMPDIR (tools/fuzz.sh points it at a tmpfs folder that it
// removes afterwards), created on first use; each harness overwrites its files in it.
inline const std::filesystem::path& ScratchDir() {
  static const std::filesystem::path* dir = [] {
    auto* d = new std::filesystem::path(std::filesystem::temp_directory_path() /
                                        ("gcpstereo-fuzz-" + std::to_string(::getpid())));
    std::filesystem::create_directories(*d);
    // Quiet: the readers' warnings would flood libFuzzer's output.
    spdlog::set_level(spdlog::level::off);
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(ScratchDir(), ec);
    });
    return d;
  }();
  return *dir;
}

inline void WriteBytes(const std::filesystem::path& path, std::string_view bytes) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

inline std::string_view AsView(const std::uint8_t* data, std::size_t size) {
  return std::string_view(reinterpret_cast<const char*>(data), size);
}

// The input cut at each kSplit into exactly `parts` pieces (missing pieces are empty, the last
// piece keeps any further separators).
inline std::vector<std::string_view> Split(std::string_view input, std::size_t parts) {
  std::vector<std::string_view> out;
  while (out.size() + 1 < parts) {
    const std::size_t at = input.find(kSplit);
    if (at == std::string_view::npos) break;
    out.push_back(input.substr(0, at));
    input.remove_prefix(at + kSplit.size());
  }
  out.push_back(input);
  out.resize(parts);
  return out;
}

// Aborts (a finding) when a refusal's message does not name `name` (a path or a file name).
inline void RequireNamed(const Error& e, const std::string& name) {
  if (std::string_view(e.what()).find(name) == std::string_view::npos) {
    std::fprintf(stderr, "error message does not name '%s': %s\n", name.c_str(), e.what());
    std::abort();
  }
}

}  // namespace gcpstereo::fuzz
