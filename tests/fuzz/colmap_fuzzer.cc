// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// libFuzzer harness: io::ReadColmapModel on a sparse folder whose cameras, images and points3D
// files (extension GCPSTEREO_FUZZ_EXTENSION: bin or txt, one build each) are the fuzz input's three
// parts (fuzz::kSplit), then io::MakeColmapPinhole on each camera of at most 4096x4096 px: the
// loader converts a camera only after reading an image of its size, so a real image bounds it.
#include "fuzz_util.h"
#include "gcpstereo/io/colmap_io.h"

#ifndef GCPSTEREO_FUZZ_EXTENSION
#error "GCPSTEREO_FUZZ_EXTENSION (bin or txt) must be defined"
#endif

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace gcpstereo;
  const std::filesystem::path dir = fuzz::ScratchDir() / "sparse";
  const std::vector<std::string_view> parts = fuzz::Split(fuzz::AsView(data, size), 3);
  fuzz::WriteBytes(dir / "cameras." GCPSTEREO_FUZZ_EXTENSION, parts[0]);
  fuzz::WriteBytes(dir / "images." GCPSTEREO_FUZZ_EXTENSION, parts[1]);
  fuzz::WriteBytes(dir / "points3D." GCPSTEREO_FUZZ_EXTENSION, parts[2]);
  try {
    const io::ColmapModel model = io::ReadColmapModel(dir.string());
    for (const auto& [id, camera] : model.cameras) {
      if (camera.width <= 4096 && camera.height <= 4096) {
        io::MakeColmapPinhole(camera, model.sparse_dir);
      }
    }
  } catch (const Error& e) {
    fuzz::RequireNamed(e, dir.string());
  }
  return 0;
}
