// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// libFuzzer harness: io::KittiNeighbourScans with a fuzzed velodyne_points/timestamps.txt and four
// (empty) scans 0000000000…0000000003.bin, for frame 0000000001.
#include "fuzz_util.h"
#include "gcpstereo/io/dataset_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace gcpstereo;
  const std::filesystem::path drive = fuzz::ScratchDir() / "drive";
  static const bool scans_written = [&] {
    for (int i = 0; i < 4; ++i) {
      fuzz::WriteBytes(
          drive / "velodyne_points" / "data" / ("000000000" + std::to_string(i) + ".bin"), "");
    }
    return true;
  }();
  (void)scans_written;
  const std::string stamps = (drive / "velodyne_points" / "timestamps.txt").string();
  fuzz::WriteBytes(stamps, fuzz::AsView(data, size));
  try {
    io::KittiNeighbourScans(drive.string(), "0000000001", 0.25);
  } catch (const Error& e) {
    fuzz::RequireNamed(e, stamps);
  }
  return 0;
}
