// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// libFuzzer harness: io::LoadMiddleburyDataset on a minimal 2001/2003 folder (im2, im6 and the
// ground truth of the pair, 8x6 pixels) in which one file is the fuzz input. The input's first byte
// chooses that file: 0 disp2.pgm (8-bit PGM, the 2001 sets), 1 disp2.png (2003), 2 nonocc.png (a
// mask), 3 im2.png (the reference image itself); the rest of the input is its bytes.
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "fuzz_util.h"
#include "gcpstereo/io/dataset_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace gcpstereo;
  if (size < 1) return 0;
  static const char* const kTargets[] = {"disp2.pgm", "disp2.png", "nonocc.png", "im2.png"};
  const std::string target = kTargets[data[0] % 4];
  const std::filesystem::path dir = fuzz::ScratchDir() / "middlebury";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const cv::Mat image(6, 8, CV_8UC3, cv::Scalar(40, 90, 160));
  const cv::Mat disparity(6, 8, CV_8UC1, cv::Scalar(12));
  cv::imwrite((dir / "im2.png").string(), image);
  cv::imwrite((dir / "im6.png").string(), image);
  if (target == "disp2.pgm") {
    cv::imwrite((dir / "disp6.pgm").string(), disparity);
  } else {
    cv::imwrite((dir / "disp2.png").string(), disparity);
    cv::imwrite((dir / "disp6.png").string(), disparity);
  }
  fuzz::WriteBytes(dir / target, fuzz::AsView(data + 1, size - 1));
  io::DatasetRequest request;
  request.format = "middlebury";
  request.path = dir.string();
  request.reference = "im2";
  request.neighbors = {"im6"};
  try {
    io::LoadMiddleburyDataset(request);
  } catch (const Error& e) {
    fuzz::RequireNamed(e, target);
  }
  return 0;
}
