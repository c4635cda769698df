// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// libFuzzer harness: io::ReadStrechaCamera (Strecha's 9-line .camera text files).
#include "fuzz_util.h"
#include "gcpstereo/io/camera_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace gcpstereo;
  const std::string path = (fuzz::ScratchDir() / "0000.png.camera").string();
  fuzz::WriteBytes(path, fuzz::AsView(data, size));
  try {
    io::ReadStrechaCamera(path);
  } catch (const Error& e) {
    fuzz::RequireNamed(e, path);
  }
  return 0;
}
