// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// A written synthetic set loads through the io module's Strecha loader like real data.
#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "gcpstereo/io/dataset_io.h"
#include "gcpstereo/synth/writer.h"
#include "test_data.h"

namespace gcpstereo::synth {
namespace {

TEST(SynthWriterTest, StrechaLoaderReadsTheWrittenSet) {
  SynthOptions options;
  options.preset = "tiny";
  options.supersampling = 1;
  const SyntheticScene scene = GenerateScene(options);
  const std::string dir_a = testing::MakeTempDir("synth_load");
  WriteScene(scene, options, dir_a);
  const int ref = scene.reference_index;
  // The Strecha loader takes the synthetic set like real data, ground truth included.
  io::DatasetRequest request;
  request.format = "strecha";
  request.path = dir_a;
  request.reference = "0005";
  request.neighbors = {"0004", "0006"};
  const Dataset dataset = io::LoadDataset(request);
  EXPECT_EQ(dataset.reference.name, "0005");
  ASSERT_EQ(dataset.neighbors.size(), 2u);
  EXPECT_EQ(cv::norm(dataset.reference.image, scene.views[ref].image, cv::NORM_L1), 0.0);
  ASSERT_TRUE(dataset.ground_truth.HasDepth());
  EXPECT_FALSE(dataset.ground_truth.sigma.empty());
}

}  // namespace
}  // namespace gcpstereo::synth
