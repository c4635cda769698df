// The synthetic `tiny` scene (seed 7) that the pipeline tests run on.
#pragma once

#include <string>

#include "gcpstereo/synth/generator.h"
#include "gcpstereo/synth/writer.h"
#include "test_data.h"

namespace gcpstereo::testing {

// A new temporary folder (named after `prefix`) holding the tiny scene under `data/`; returns the
// folder.
inline std::string WriteTinyData(const std::string& prefix) {
  const std::string dir = MakeTempDir(prefix);
  synth::SynthOptions options;
  options.preset = "tiny";
  options.seed = 7;
  synth::WriteScene(synth::GenerateScene(options), options, dir + "/data");
  return dir;
}

}  // namespace gcpstereo::testing
