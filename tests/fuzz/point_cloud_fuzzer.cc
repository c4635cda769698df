// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// libFuzzer harness: io::ReadPointCloud on a point cloud file whose extension is
// GCPSTEREO_FUZZ_EXTENSION (tests/fuzz/CMakeLists.txt builds it once per format: ply and pcd go
// through our header check to PCL, bin is a KITTI Velodyne scan).
#include "fuzz_util.h"
#include "gcpstereo/io/point_cloud_io.h"

#ifndef GCPSTEREO_FUZZ_EXTENSION
#error "GCPSTEREO_FUZZ_EXTENSION (the file extension, e.g. \"ply\") must be defined"
#endif

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace gcpstereo;
  const std::string path = (fuzz::ScratchDir() / ("cloud." GCPSTEREO_FUZZ_EXTENSION)).string();
  fuzz::WriteBytes(path, fuzz::AsView(data, size));
  try {
    io::ReadPointCloud(path);
  } catch (const Error& e) {
    fuzz::RequireNamed(e, path);
  }
  return 0;
}
