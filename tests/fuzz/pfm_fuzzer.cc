// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// libFuzzer harness: io::ReadPfm (depth, disparity and ground-truth maps).
#include "fuzz_util.h"
#include "gcpstereo/io/pfm.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace gcpstereo;
  const std::string path = (fuzz::ScratchDir() / "map.pfm").string();
  fuzz::WriteBytes(path, fuzz::AsView(data, size));
  try {
    io::ReadPfm(path);
  } catch (const Error& e) {
    fuzz::RequireNamed(e, path);
  }
  return 0;
}
