// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/io/atomic_file.h"

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "gcpstereo/core/error.h"
#include "gcpstereo/io/pfm.h"
#include "test_data.h"

namespace gcpstereo::io {
namespace {

namespace fs = std::filesystem;

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

TEST(AtomicFile, WritesThroughPartialAndRenames) {
  const std::string dir = testing::MakeTempDir("io-atomic");
  const std::string path = dir + "/out.txt";
  std::string seen_temp;
  WriteFileAtomically(path, [&](const std::string& temp_path) {
    seen_temp = temp_path;
    EXPECT_FALSE(fs::exists(path));  // nothing under the final name while writing
    std::ofstream(temp_path) << "hello";
  });
  EXPECT_EQ(seen_temp, path + ".partial");
  EXPECT_EQ(ReadText(path), "hello");
  EXPECT_FALSE(fs::exists(path + ".partial"));
}

TEST(AtomicFile, ThrowingWriterLeavesNoFile) {
  const std::string dir = testing::MakeTempDir("io-atomic");
  const std::string path = dir + "/out.txt";
  EXPECT_THROW(WriteFileAtomically(path,
                                   [](const std::string& temp_path) {
                                     std::ofstream(temp_path) << "half written";
                                     throw std::runtime_error("disk on fire");
                                   }),
               std::runtime_error);
  EXPECT_FALSE(fs::exists(path));
  EXPECT_FALSE(fs::exists(path + ".partial"));
}

TEST(AtomicFile, ThrowingWriterKeepsPreviousFile) {
  const std::string dir = testing::MakeTempDir("io-atomic");
  const std::string path = dir + "/out.txt";
  WriteBytesAtomically(path, "old", 3);
  EXPECT_THROW(WriteFileAtomically(path,
                                   [](const std::string& temp_path) {
                                     std::ofstream(temp_path) << "new";
                                     throw IoError(temp_path, "failed");
                                   }),
               IoError);
  EXPECT_EQ(ReadText(path), "old");
  EXPECT_FALSE(fs::exists(path + ".partial"));
}

TEST(AtomicFile, WriterThatCreatesNothingIsAnError) {
  const std::string dir = testing::MakeTempDir("io-atomic");
  const std::string path = dir + "/out.txt";
  try {
    WriteFileAtomically(path, [](const std::string&) {});
    FAIL() << "expected IoError";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("did not produce the temporary file"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(fs::exists(path));
}

TEST(AtomicFile, MissingFolderIsNamed) {
  const std::string dir = testing::MakeTempDir("io-atomic");
  const std::string path = dir + "/no/such/folder/out.pfm";
  try {
    WritePfm(path, cv::Mat(2, 2, CV_32F, cv::Scalar(1.0f)));
    FAIL() << "expected IoError";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": cannot write: folder"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace gcpstereo::io
