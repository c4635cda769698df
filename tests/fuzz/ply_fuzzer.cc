// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// libFuzzer harness: io::ReadPointCloud on a PLY point cloud (PCL behind our header check).
#include "fuzz_util.h"
#include "gcpstereo/io/point_cloud_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace gcpstereo;
  const std::string path = (fuzz::ScratchDir() / "cloud.ply").string();
  fuzz::WriteBytes(path, fuzz::AsView(data, size));
  try {
    io::ReadPointCloud(path);
  } catch (const Error& e) {
    fuzz::RequireNamed(e, path);
  }
  return 0;
}
