// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// libFuzzer harness: io::LoadKittiRawDataset on a minimal drive (one frame, 8x6 images) whose
// calib_cam_to_cam.txt and calib_velo_to_cam.txt are the fuzz input's two parts (fuzz::kSplit).
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "fuzz_util.h"
#include "gcpstereo/io/dataset_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace gcpstereo;
  const std::filesystem::path date = fuzz::ScratchDir() / "2011_09_26";
  const std::filesystem::path drive = date / "2011_09_26_drive_0001_sync";
  static const bool images_written = [&] {
    const cv::Mat image(6, 8, CV_8UC3, cv::Scalar(40, 90, 160));
    for (const char* camera : {"image_02", "image_03"}) {
      std::filesystem::create_directories(drive / camera / "data");
      cv::imwrite((drive / camera / "data" / "0000000000.png").string(), image);
    }
    return true;
  }();
  (void)images_written;
  const std::vector<std::string_view> parts = fuzz::Split(fuzz::AsView(data, size), 2);
  fuzz::WriteBytes(date / "calib_cam_to_cam.txt", parts[0]);
  fuzz::WriteBytes(date / "calib_velo_to_cam.txt", parts[1]);
  io::DatasetRequest request;
  request.format = "kitti_raw";
  request.path = drive.string();
  request.reference = "0000000000";
  try {
    io::LoadKittiRawDataset(request);
  } catch (const Error& e) {
    fuzz::RequireNamed(e, "calib_");
  }
  return 0;
}
