// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/io/atomic_file.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <system_error>

#include "gcpstereo/core/error.h"

namespace fs = std::filesystem;

namespace gcpstereo::io {

void WriteFileAtomically(const std::string& path,
                         const std::function<void(const std::string& temp_path)>& write) {
  if (path.empty()) throw IoError(path, "empty output path");
  const fs::path final_path(path);
  const fs::path parent = final_path.has_parent_path() ? final_path.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(parent, ec)) {
    throw IoError(path, "cannot write: folder '" + parent.string() + "' does not exist");
  }
  if (fs::is_directory(final_path, ec)) {
    throw IoError(path, "cannot write: a folder of that name exists");
  }
  const std::string temp_path = path + ".partial";
  auto remove_temp = [&temp_path] {
    std::error_code ignored;
    fs::remove(temp_path, ignored);
  };
  try {
    write(temp_path);
    if (!fs::is_regular_file(temp_path, ec)) {
      throw IoError(path, "writer did not produce the temporary file '" + temp_path + "'");
    }
    fs::rename(temp_path, final_path, ec);
    if (ec) throw IoError(path, "cannot rename '" + temp_path + "' onto it: " + ec.message());
  } catch (...) {
    remove_temp();
    throw;
  }
}

void WriteBytesAtomically(const std::string& path, const void* data, std::size_t size) {
  WriteFileAtomically(path, [&](const std::string& temp_path) {
    std::ofstream out(temp_path, std::ios::binary | std::ios::trunc);
    if (!out) throw IoError(path, std::string("cannot open for writing: ") + std::strerror(errno));
    out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
    out.flush();
    if (!out) throw IoError(path, "write failed (disk full?)");
  });
}

std::string ReadFileBytes(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw IoError(path, "file not found");
  if (fs::is_directory(path, ec)) throw IoError(path, "is a folder, expected a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path, std::string("cannot open file: ") + std::strerror(errno));
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  in.seekg(0, std::ios::beg);
  if (size < 0) throw IoError(path, "cannot determine the file size");
  std::string bytes(static_cast<std::size_t>(size), '\0');
  if (size > 0) in.read(&bytes[0], size);
  if (!in || in.gcount() != size) throw IoError(path, "read failed");
  return bytes;
}

}  // namespace gcpstereo::io
