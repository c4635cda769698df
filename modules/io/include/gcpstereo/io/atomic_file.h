// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <cstddef>
#include <functional>
#include <string>

namespace gcpstereo::io {

// Writes `path` so that no partial file ever appears under its final name (the contract's "no
// partial output files left behind"): `write` is called with temp_path = path + ".partial" (same
// folder, so the final rename is atomic on POSIX file systems) and must create that file; the temp
// file is then renamed onto `path`, replacing any previous file. If `write` throws, or does not
// create the temp file, or the rename fails, the temp file is removed and the error propagates
// (an IoError naming `path` for the latter two). Throws IoError when the folder does not exist.
void WriteFileAtomically(const std::string& path,
                         const std::function<void(const std::string& temp_path)>& write);

// Writes `size` bytes to `path` atomically (binary, through WriteFileAtomically).
void WriteBytesAtomically(const std::string& path, const void* data, std::size_t size);

// Reads a whole file into memory; throws IoError ("cannot open file") when it cannot be read.
std::string ReadFileBytes(const std::string& path);

}  // namespace gcpstereo::io
