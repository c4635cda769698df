// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/core/logging.h"

#include <spdlog/sinks/basic_file_sink.h>

#include "gcpstereo/core/error.h"

namespace gcpstereo {

void SetLogLevel(const std::string& level) {
  const spdlog::level::level_enum parsed = spdlog::level::from_str(level);
  if (parsed == spdlog::level::off && level != "off") {
    throw ConfigError(ViolatedConstraint("log level", level,
                                         "one of trace, debug, info, warn, error, off"));
  }
  spdlog::set_level(parsed);
}

void AddLogFile(const std::string& path) {
  std::shared_ptr<spdlog::sinks::basic_file_sink_mt> sink;
  try {
    sink = std::make_shared<spdlog::sinks::basic_file_sink_mt>(path, /*truncate=*/true);
  } catch (const spdlog::spdlog_ex& e) {
    throw IoError(path, std::string("cannot open log file: ") + e.what());
  }
  sink->set_level(spdlog::level::debug);
  spdlog::default_logger()->sinks().push_back(sink);
}

void RemoveLogFiles() {
  auto& sinks = spdlog::default_logger()->sinks();
  for (auto it = sinks.begin(); it != sinks.end();) {
    if (std::dynamic_pointer_cast<spdlog::sinks::basic_file_sink_mt>(*it)) {
      (*it)->flush();
      it = sinks.erase(it);
    } else {
      ++it;
    }
  }
}

}  // namespace gcpstereo
