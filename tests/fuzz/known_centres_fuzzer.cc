// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// libFuzzer harness: io::ReadKnownCentres (dataset.align_centres: `name X Y Z` per line, COLMAP
// model_aligner's convention).
#include "fuzz_util.h"
#include "gcpstereo/io/colmap_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace gcpstereo;
  const std::string path = (fuzz::ScratchDir() / "centres.txt").string();
  fuzz::WriteBytes(path, fuzz::AsView(data, size));
  try {
    io::ReadKnownCentres(path);
  } catch (const Error& e) {
    fuzz::RequireNamed(e, path);
  }
  return 0;
}
