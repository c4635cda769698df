// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// libFuzzer harness: pipeline::LoadedConfig::Load, the YAML configuration and the --set overrides.
// The input is the YAML file, then (after fuzz::kSplit) the overrides, one KEY=VALUE per line.
#include "fuzz_util.h"
#include "gcpstereo/pipeline/pipeline_config.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace gcpstereo;
  const std::vector<std::string_view> parts = fuzz::Split(fuzz::AsView(data, size), 2);
  const std::string path = (fuzz::ScratchDir() / "config.yaml").string();
  fuzz::WriteBytes(path, parts[0]);
  std::vector<std::string> overrides;
  std::string_view rest = parts[1];
  while (!rest.empty()) {
    const std::size_t end = rest.find('\n');
    overrides.emplace_back(rest.substr(0, end));
    if (end == std::string_view::npos) break;
    rest.remove_prefix(end + 1);
  }
  try {
    pipeline::LoadedConfig config;
    config.Load(path, overrides);
  } catch (const Error&) {
    // Refused: the messages name the file and line or the --set override (checked by the unit
    // tests; a message may also name only the key, for a cross-key check).
  }
  return 0;
}
