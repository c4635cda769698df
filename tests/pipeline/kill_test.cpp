// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Runs killed with SIGKILL (no destructor, no handler runs) lose nothing: the gcpstereo executable
// runs as a child process on the synthetic `tiny` set and is killed as soon as its log (stdout,
// one line per stage as it starts) reaches a given stage — deterministic points, no timing. Then
// the output folder's previous results are byte for byte what they were, the next run completes,
// and a scene run killed in the middle of a view reuses the views it had finished.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "gcpstereo/synth/generator.h"
#include "gcpstereo/synth/writer.h"
#include "test_data.h"
#include "tiny_data.h"

extern char** environ;

namespace gcpstereo::pipeline {
namespace {

using gcpstereo::testing::ReadFile;
namespace fs = std::filesystem;

struct ChildResult {
  bool killed = false;  // by our SIGKILL
  int exit_code = -1;   // when it exited by itself
  std::string output;   // its stdout up to the end or the kill
};

// Runs gcpstereo with `args`; when `kill_after` is not empty, kills the child with SIGKILL as soon
// as a line of its stdout contains every string of `kill_after` in order (one after another, each
// on a later line than the one before).
ChildResult RunChild(const std::vector<std::string>& args,
                     const std::vector<std::string>& kill_after) {
  int pipe_fds[2];
  if (pipe(pipe_fds) != 0) throw std::runtime_error("pipe failed");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_addclose(&actions, pipe_fds[0]);
  posix_spawn_file_actions_addclose(&actions, pipe_fds[1]);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  std::vector<std::string> argv_strings = {GCPSTEREO_EXECUTABLE};
  argv_strings.insert(argv_strings.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_strings) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int spawned =
      posix_spawn(&pid, GCPSTEREO_EXECUTABLE, &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(pipe_fds[1]);
  if (spawned != 0) {
    close(pipe_fds[0]);
    throw std::runtime_error("posix_spawn failed");
  }
  ChildResult result;
  FILE* in = fdopen(pipe_fds[0], "r");
  size_t next = 0;  // the next string of kill_after to see
  char buffer[4096];
  while (!kill_after.empty() && next < kill_after.size() && std::fgets(buffer, sizeof buffer, in)) {
    result.output += buffer;
    if (std::string(buffer).find(kill_after[next]) != std::string::npos) ++next;
  }
  if (!kill_after.empty() && next == kill_after.size()) kill(pid, SIGKILL);
  while (std::fgets(buffer, sizeof buffer, in)) result.output += buffer;
  fclose(in);
  int status = 0;
  waitpid(pid, &status, 0);
  result.killed = WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL;
  if (WIFEXITED(status)) result.exit_code = WEXITSTATUS(status);
  return result;
}

// Every regular file under `dir` (relative name → bytes), but run.log (the log of the latest run,
// written as it goes, so a killed run's is kept for reading) and the staging folders of killed
// runs (hidden, removed by the next run in the folder).
std::map<std::string, std::string> Snapshot(const std::string& dir) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    const std::string relative = fs::relative(entry.path(), dir).string();
    if (!entry.is_regular_file() || entry.path().filename() == "run.log" ||
        relative.find(".gcpstereo-staging-") != std::string::npos) {
      continue;
    }
    files[relative] = ReadFile(entry.path().string());
  }
  return files;
}

std::vector<std::string> StagingFolders(const std::string& dir) {
  std::vector<std::string> found;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.find(".gcpstereo-staging-") != std::string::npos ||
        entry.path().extension() == ".partial") {
      found.push_back(entry.path().string());
    }
  }
  return found;
}

class KilledRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { dir_ = new std::string(testing::WriteTinyData("gcpstereo-kill")); }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }

  // `gcpstereo run` arguments on tiny; `labels` differ between the previous and the killed run, so
  // that the killed run's outputs differ from the previous ones.
  static std::vector<std::string> Args(const std::string& out, const std::string& reference,
                                       int labels) {
    const std::string data = *dir_ + "/data";
    std::vector<std::string> args = {"run", "/dev/null", "-o", out};
    for (const std::string& set :
         {"dataset.path=" + data, "dataset.reference=" + reference,
          "labels.count=" + std::to_string(labels), std::string("gcp.sources=[lidar]"),
          "gcp.lidar.path=" + data + "/gt/laser.ply", std::string("gcp.downsample=8"),
          std::string("optimizer.tiles=[2, 2]"), std::string("optimizer.refinement=parabola"),
          std::string("scene_mesh.depth=7"), std::string("eval.scene.max_samples=20000"),
          std::string("runtime.log_level=info")}) {
      args.push_back("--set");
      args.push_back(set);
    }
    return args;
  }

  static std::string* dir_;
};
std::string* KilledRun::dir_ = nullptr;

TEST_F(KilledRun, KilledAtAnyStageLeavesThePreviousResultsAndTheNextRunCompletes) {
  const std::string out = *dir_ + "/view";
  ASSERT_EQ(RunChild(Args(out, "0005", 32), {}).exit_code, 0);
  const std::map<std::string, std::string> before = Snapshot(out);
  ASSERT_TRUE(before.count("depth.pfm") && before.count("report.json") && before.count("mesh.ply"));

  // The stages' log lines as each starts (run.cc, StageClock); "write" is the last, where the
  // outputs are written in staging before they move into place.
  for (const char* stage : {"load …", "gcps …", "propagation …", "cost_and_optimization …",
                            "evaluation …", "mesh …", "write …"}) {
    const ChildResult killed = RunChild(Args(out, "0005", 40), {stage});
    ASSERT_TRUE(killed.killed) << "not killed at '" << stage << "': " << killed.output;
    EXPECT_TRUE(Snapshot(out) == before) << "the previous results changed, killed at " << stage;
  }
  EXPECT_FALSE(StagingFolders(out).empty());  // the killed runs' staging folders remain

  const ChildResult next = RunChild(Args(out, "0005", 40), {});
  ASSERT_EQ(next.exit_code, 0) << next.output;
  const std::map<std::string, std::string> after = Snapshot(out);
  EXPECT_TRUE(after.at("depth.pfm") != before.at("depth.pfm"));  // the new run's result
  EXPECT_TRUE(StagingFolders(out).empty()) << StagingFolders(out).front();
}

TEST_F(KilledRun, SceneKilledInTheMiddleOfAViewResumesWithoutRedoingFinishedViews) {
  const std::string out = *dir_ + "/scene";
  // Killed during the third view's optimisation: 0003 and 0004 are finished.
  const ChildResult killed =
      RunChild(Args(out, "all", 32), {"scene: view 0005 (3/5)", "cost_and_optimization …"});
  ASSERT_TRUE(killed.killed) << killed.output;
  std::map<std::string, std::string> finished_reports;
  std::map<std::string, fs::file_time_type> finished_times;
  for (const char* view : {"0003", "0004"}) {
    const std::string report = out + "/views/" + view + "/report.json";
    ASSERT_TRUE(fs::exists(report)) << report;
    finished_reports[view] = ReadFile(report);
    finished_times[view] = fs::last_write_time(out + "/views/" + view + "/depth.pfm");
  }
  EXPECT_FALSE(fs::exists(out + "/views/0005/report.json"));
  EXPECT_FALSE(fs::exists(out + "/report.json"));

  const ChildResult resumed = RunChild(Args(out, "all", 32), {});
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  const nlohmann::json report = nlohmann::json::parse(ReadFile(out + "/report.json"));
  std::map<std::string, std::string> status;
  for (const nlohmann::json& v : report["views"]) status[v["name"]] = v["status"];
  EXPECT_EQ(status["0003"], "reused");
  EXPECT_EQ(status["0004"], "reused");
  EXPECT_EQ(status["0005"], "done");
  EXPECT_EQ(status["0007"], "done");
  for (const char* view : {"0003", "0004"}) {
    EXPECT_NE(resumed.output.find(std::string("view ") + view + " is complete"), std::string::npos)
        << resumed.output;
    EXPECT_EQ(ReadFile(out + "/views/" + view + "/report.json"), finished_reports[view]);
    EXPECT_TRUE(fs::last_write_time(out + "/views/" + view + "/depth.pfm") == finished_times[view]);
  }
  EXPECT_TRUE(fs::exists(out + "/mesh.ply"));
  EXPECT_TRUE(StagingFolders(out).empty()) << StagingFolders(out).front();
}

}  // namespace
}  // namespace gcpstereo::pipeline
