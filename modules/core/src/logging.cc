// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/core/logging.h"

#include <spdlog/sinks/basic_file_sink.h>
#include <spdlog/sinks/stdout_color_sinks.h>

#include "gcpstereo/core/error.h"

namespace gcpstereo {

namespace {

// Routes each message by level: below warn to `low`, warn and above to `high`.
class SplitSink : public spdlog::sinks::base_sink<std::mutex> {
 public:
  SplitSink() {
    low_ = std::make_shared<spdlog::sinks::stdout_color_sink_mt>();
    high_ = std::make_shared<spdlog::sinks::stderr_color_sink_mt>();
  }

 protected:
  void sink_it_(const spdlog::details::log_msg& msg) override {
    (msg.level >= spdlog::level::warn ? high_ : low_)->log(msg);
  }
  void flush_() override {
    low_->flush();
    high_->flush();
  }
  void set_pattern_(const std::string& pattern) override {
    low_->set_pattern(pattern);
    high_->set_pattern(pattern);
  }
  void set_formatter_(std::unique_ptr<spdlog::formatter> formatter) override {
    low_->set_formatter(formatter->clone());
    high_->set_formatter(std::move(formatter));
  }

 private:
  std::shared_ptr<spdlog::sinks::sink> low_, high_;
};

}  // namespace

void InstallConsoleLogger() {
  auto logger = std::make_shared<spdlog::logger>("gcpstereo", std::make_shared<SplitSink>());
  logger->set_pattern("[%H:%M:%S] %^%l%$: %v");
  spdlog::set_default_logger(logger);
}

void SetLogLevel(const std::string& level) {
  const spdlog::level::level_enum parsed = spdlog::level::from_str(level);
  if (parsed == spdlog::level::off && level != "off") {
    throw ConfigError(
        ViolatedConstraint("log level", level, "one of trace, debug, info, warn, error, off"));
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

void RemoveLogFile(const std::string& path) {
  auto& sinks = spdlog::default_logger()->sinks();
  for (auto it = sinks.begin(); it != sinks.end();) {
    const auto file = std::dynamic_pointer_cast<spdlog::sinks::basic_file_sink_mt>(*it);
    if (file && file->filename() == path) {
      file->flush();
      it = sinks.erase(it);
    } else {
      ++it;
    }
  }
}

void LogToFilesOnly(const std::string& line) {
  const spdlog::details::log_msg message(spdlog::default_logger()->name(), spdlog::level::err,
                                         line);
  for (const auto& sink : spdlog::default_logger()->sinks()) {
    if (!std::dynamic_pointer_cast<spdlog::sinks::basic_file_sink_mt>(sink)) continue;
    sink->log(message);
    sink->flush();
  }
}

}  // namespace gcpstereo
