// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/config/schema.h"

#include <fstream>

#include <gtest/gtest.h>

#include "gcpstereo/core/error.h"
#include "test_data.h"

namespace gcpstereo::config {
namespace {

struct Options {
  double lambda_s = 20.0;
  int count = 360;
  bool refine = true;
  std::string space = "depth";
  std::string path;
  std::vector<std::string> sources{"lidar"};
  std::vector<int> tiles{2, 2};
  std::optional<double> min;
  std::optional<int> levels = 16;
};

class SchemaTest : public ::testing::Test {
 protected:
  void SetUp() override {
    schema.Add("optimizer.lambda_s", &o.lambda_s, Range::AtLeast(0.0),
               {"smoothness weight", "", "λs"});
    schema.Add("labels.count", &o.count, Range::Between(2, 4096), {"number of labels"});
    schema.Add("optimizer.refine", &o.refine, {"sub-label refinement"});
    schema.Add("labels.space", &o.space, {"depth", "inverse_depth", "disparity"}, {"spacing"});
    schema.Add("dataset.path", &o.path, {}, {"folder"});
    schema.Add("gcp.sources", &o.sources, {"lidar", "depth_map", "stereo"}, {"sources"});
    schema.Add("optimizer.tiles", &o.tiles, 2, Range::AtLeast(1), {"tiles"});
    schema.Add("labels.min", &o.min, Range::GreaterThan(0.0), {"min", "m"});
    schema.Add("labels.levels", &o.levels, Range::Between(2, 4096), {"levels"});
  }

  std::string ErrorOf(const std::string& yaml) {
    try {
      schema.LoadString(yaml, "test.yaml");
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "no error";
  }

  Options o;
  Schema schema;
};

TEST_F(SchemaTest, AppliesValuesOfEveryType) {
  schema.LoadString(
      "optimizer:\n  lambda_s: 12.5\n  refine: false\n  tiles: [3, 4]\n"
      "labels: {count: 64, space: disparity, min: 0.5}\n"
      "dataset:\n  path: /data/x\n"
      "gcp:\n  sources: [stereo, lidar]\n",
      "test.yaml");
  EXPECT_EQ(o.lambda_s, 12.5);
  EXPECT_FALSE(o.refine);
  EXPECT_EQ(o.tiles, (std::vector<int>{3, 4}));
  EXPECT_EQ(o.count, 64);
  EXPECT_EQ(o.space, "disparity");
  ASSERT_TRUE(o.min.has_value());
  EXPECT_EQ(*o.min, 0.5);
  EXPECT_EQ(o.path, "/data/x");
  EXPECT_EQ(o.sources, (std::vector<std::string>{"stereo", "lidar"}));
  EXPECT_TRUE(schema.IsSet("labels.count"));
  EXPECT_FALSE(schema.IsSet("nothing"));
}

TEST_F(SchemaTest, EmptyListAndAutoAndEmptyDocument) {
  schema.LoadString("gcp:\n  sources: []\nlabels:\n  min: auto\n", "t");
  EXPECT_TRUE(o.sources.empty());
  EXPECT_FALSE(o.min.has_value());
  schema.LoadString("", "empty.yaml");
  EXPECT_EQ(o.lambda_s, 20.0);
}

TEST_F(SchemaTest, IntegerOrAuto) {
  EXPECT_NE(schema.ToYaml().find("levels: 16"), std::string::npos);
  schema.LoadString("labels:\n  levels: auto\n", "t");
  EXPECT_FALSE(o.levels.has_value());
  EXPECT_NE(schema.ToYaml().find("levels: auto"), std::string::npos);
  schema.ApplyOverride("labels.levels=40");
  ASSERT_TRUE(o.levels.has_value());
  EXPECT_EQ(*o.levels, 40);
  EXPECT_EQ(ErrorOf("labels:\n  levels: 2.5\n"),
            "test.yaml:2: labels.levels = 2.5. Violated constraint: an integer or auto");
  EXPECT_EQ(ErrorOf("labels:\n  levels: 1\n"),
            "test.yaml:2: labels.levels = 1. Violated constraint: 2 <= labels.levels <= 4096");
  EXPECT_NE(schema.Describe().find("labels.levels  (integer or auto, default 16"),
            std::string::npos);
}

TEST_F(SchemaTest, UnknownKeyNamesFileLineAndSuggestion) {
  EXPECT_EQ(ErrorOf("labels:\n  count: 3\noptimizer:\n  lamda_s: 3\n"),
            "test.yaml:4: unknown configuration key 'optimizer.lamda_s' (did you mean "
            "'optimizer.lambda_s'?)");
  EXPECT_EQ(ErrorOf("colour: red\n"), "test.yaml:1: unknown configuration key 'colour'");
}

// YAML lets a later key replace an earlier one silently; a configuration that says a key twice
// is a mistake (which one did the user mean?), so it fails naming both lines, also across two
// copies of a section. A section may repeat with other keys (effective_config.yaml does).
TEST_F(SchemaTest, KeyGivenTwiceNamesBothLines) {
  EXPECT_EQ(ErrorOf("labels:\n  count: 3\n  count: 5\n"),
            "test.yaml:3: labels.count is given twice (first on line 2)");
  EXPECT_EQ(ErrorOf("labels:\n  count: 3\noptimizer:\n  lambda_s: 3\nlabels:\n  count: 4\n"),
            "test.yaml:6: labels.count is given twice (first on line 2)");
  EXPECT_EQ(ErrorOf("labels:\n  count: 3\noptimizer:\n  lambda_s: 3\nlabels:\n  min: 4\n"),
            "no error");
}

TEST_F(SchemaTest, OutOfRangeNamesKeyValueAndBound) {
  EXPECT_EQ(ErrorOf("optimizer:\n  lambda_s: -1\n"),
            "test.yaml:2: optimizer.lambda_s = -1. Violated constraint: optimizer.lambda_s >= 0");
  EXPECT_EQ(ErrorOf("labels:\n  count: 1\n"),
            "test.yaml:2: labels.count = 1. Violated constraint: 2 <= labels.count <= 4096");
  EXPECT_EQ(ErrorOf("labels:\n  min: 0\n"),
            "test.yaml:2: labels.min = 0. Violated constraint: labels.min > 0");
  EXPECT_EQ(ErrorOf("optimizer:\n  tiles: [0, 2]\n"),
            "test.yaml:2: optimizer.tiles = [0, 2]. Violated constraint: optimizer.tiles >= 1");
}

TEST_F(SchemaTest, WrongTypesAreRejected) {
  EXPECT_EQ(ErrorOf("optimizer:\n  lambda_s: fast\n"),
            "test.yaml:2: optimizer.lambda_s = fast. Violated constraint: a number");
  EXPECT_EQ(ErrorOf("labels:\n  count: 2.5\n"),
            "test.yaml:2: labels.count = 2.5. Violated constraint: an integer");
  EXPECT_EQ(ErrorOf("labels:\n  space: log\n"),
            "test.yaml:2: labels.space = log. Violated constraint: one of depth, inverse_depth, "
            "disparity");
  EXPECT_EQ(ErrorOf("optimizer:\n  tiles: [2]\n"),
            "test.yaml:2: optimizer.tiles = [2]. Violated constraint: list of 2 integers");
  EXPECT_EQ(ErrorOf("optimizer: 3\n"),
            "test.yaml:1: optimizer is a section: expected a mapping of keys, got '3'");
  EXPECT_EQ(ErrorOf("optimizer:\n  refine: maybe\n"),
            "test.yaml:2: optimizer.refine = maybe. Violated constraint: true or false");
  EXPECT_EQ(ErrorOf("optimizer:\n  lambda_s: .inf\n"),
            "test.yaml:2: optimizer.lambda_s = .inf. Violated constraint: a finite number");
  // A failed value leaves the field untouched.
  EXPECT_EQ(o.count, 360);
}

TEST_F(SchemaTest, SyntaxErrorNamesLine) {
  EXPECT_EQ(ErrorOf("labels:\n  count: [1, 2\n"),
            "test.yaml:3: YAML syntax error: end of sequence flow not found");
}

// yaml-cpp runs a quoted scalar whose closing quote is missing on over the following lines (to
// the next quote of its kind or the end), which swallowed later keys silently or gave a syntax
// error lines further down. Such a scalar is refused on the line it starts, naming the key.
TEST_F(SchemaTest, UnclosedQuoteNamesItsLineAndKey) {
  // Runs on to the end: dataset.path would be "/data/x labels: count: 3 ".
  EXPECT_EQ(ErrorOf("dataset:\n  path: \"/data/x\nlabels:\n  count: 3\n"),
            "test.yaml:2: the quoted value of dataset.path is not closed on its line (missing "
            "closing \")");
  // Closed by a later quote, then a syntax error on line 4.
  EXPECT_EQ(ErrorOf("labels:\n  count: 3\ndataset:\n  path: '/data/x\nlabels:\n  space: 'depth'\n"),
            "test.yaml:4: the quoted value of dataset.path is not closed on its line (missing "
            "closing ')");
  // The end of the text without a newline.
  EXPECT_EQ(ErrorOf("dataset:\n  path: \"/data/x"),
            "test.yaml:2: the quoted value of dataset.path is not closed on its line (missing "
            "closing \")");
  // An item of a flow list, an escaped quote that does not close, a key (yaml-cpp reads the
  // run-on text as the value of labels), a top-level key.
  EXPECT_EQ(ErrorOf("gcp:\n  sources: [\"stereo\", \"lidar]\n"),
            "test.yaml:2: the quoted value of gcp.sources is not closed on its line (missing "
            "closing \")");
  EXPECT_EQ(ErrorOf("dataset:\n  path: \"a\\\"\nlabels:\n  space: \"depth\"\n"),
            "test.yaml:2: the quoted value of dataset.path is not closed on its line (missing "
            "closing \")");
  EXPECT_EQ(
      ErrorOf("labels:\n  'count: 3\n"),
      "test.yaml:2: the quoted value of labels is not closed on its line (missing closing ')");
  EXPECT_EQ(ErrorOf("\"labels:\n  count: 3\n"),
            "test.yaml:1: a quoted string is not closed on its line (missing closing \")");
  EXPECT_EQ(o.path, "");  // nothing was applied
  try {
    schema.ApplyOverride("dataset.path=\"/data/x");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "--set dataset.path=\"/data/x: the quoted value of dataset.path is not closed on "
                 "its line (missing closing \")");
  }
}

// Quoted scalars that end on their line load as before: '#' inside quotes, escaped quotes, flow
// lists of quoted items (also over two lines), tags, quoted keys, CRLF line ends.
TEST_F(SchemaTest, QuotedValuesClosedOnTheirLineLoad) {
  schema.LoadString("dataset:\n  path: \"/data/x # not a comment\"  # it's a comment\n", "t");
  EXPECT_EQ(o.path, "/data/x # not a comment");
  schema.LoadString("dataset:\n  path: \"a\\\"b\"\n", "t");
  EXPECT_EQ(o.path, "a\"b");
  schema.LoadString("dataset:\n  path: 'it''s'\n", "t");
  EXPECT_EQ(o.path, "it's");
  schema.LoadString("gcp:\n  sources: [ \"stereo\", 'lidar' ]\n", "t");
  EXPECT_EQ(o.sources, (std::vector<std::string>{"stereo", "lidar"}));
  schema.LoadString("gcp:\n  sources: [\"depth_map\",\n            'stereo']\n", "t");
  EXPECT_EQ(o.sources, (std::vector<std::string>{"depth_map", "stereo"}));
  schema.LoadString("\"labels\":\n  'space': !!str \"inverse_depth\"\n", "t");
  EXPECT_EQ(o.space, "inverse_depth");
  schema.LoadString("dataset:\r\n  path: \"/data/y\"\r\n", "t");
  EXPECT_EQ(o.path, "/data/y");
  schema.ApplyOverride("dataset.path=\"/data/a b\"");
  EXPECT_EQ(o.path, "/data/a b");
  schema.ApplyOverride("gcp.sources=['lidar', \"stereo\"]");
  EXPECT_EQ(o.sources, (std::vector<std::string>{"lidar", "stereo"}));
}

TEST_F(SchemaTest, OverridesParseYamlValues) {
  schema.ApplyOverride("gcp.sources=[stereo]");
  EXPECT_EQ(o.sources, (std::vector<std::string>{"stereo"}));
  schema.ApplyOverride("optimizer.lambda_s=7");
  EXPECT_EQ(o.lambda_s, 7.0);
  try {
    schema.ApplyOverride("optimizer.lambda=7");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "--set optimizer.lambda=7: unknown configuration key 'optimizer.lambda' (did you "
                 "mean 'optimizer.lambda_s'?)");
  }
  try {
    schema.ApplyOverride("labels.count=0");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "--set: labels.count = 0. Violated constraint: 2 <= labels.count <= 4096");
  }
  EXPECT_THROW(schema.ApplyOverride("novalue"), ConfigError);
}

TEST_F(SchemaTest, EffectiveYamlRoundTrips) {
  schema.LoadString(
      "optimizer:\n  lambda_s: 3\n  tiles: [1, 3]\nlabels:\n  min: 2\n  levels: auto\n", "t");
  const std::string yaml = schema.ToYaml();
  EXPECT_NE(yaml.find("# smoothness weight (paper: λs)"), std::string::npos) << yaml;
  Options fresh;
  Schema other;
  other.Add("optimizer.lambda_s", &fresh.lambda_s, Range::AtLeast(0.0), {"a"});
  other.Add("labels.count", &fresh.count, Range::Between(2, 4096), {"b"});
  other.Add("optimizer.refine", &fresh.refine, {"c"});
  other.Add("labels.space", &fresh.space, {"depth", "inverse_depth", "disparity"}, {"d"});
  other.Add("dataset.path", &fresh.path, {}, {"e"});
  other.Add("gcp.sources", &fresh.sources, {"lidar", "depth_map", "stereo"}, {"f"});
  other.Add("optimizer.tiles", &fresh.tiles, 2, Range::AtLeast(1), {"g"});
  other.Add("labels.min", &fresh.min, Range::GreaterThan(0.0), {"h"});
  other.Add("labels.levels", &fresh.levels, Range::Between(2, 4096), {"i"});
  other.LoadString(yaml, "effective.yaml");
  EXPECT_FALSE(fresh.levels.has_value());
  EXPECT_EQ(fresh.lambda_s, 3.0);
  EXPECT_EQ(fresh.tiles, (std::vector<int>{1, 3}));
  ASSERT_TRUE(fresh.min.has_value());
  EXPECT_EQ(*fresh.min, 2.0);
  EXPECT_EQ(fresh.sources, o.sources);
}

TEST_F(SchemaTest, MissingFileIsAnIoError) {
  try {
    schema.LoadFile("/nonexistent/config.yaml");
    FAIL();
  } catch (const IoError& e) {
    EXPECT_STREQ(e.what(), "/nonexistent/config.yaml: cannot open configuration file");
  }
}

}  // namespace
}  // namespace gcpstereo::config

namespace gcpstereo::config {
namespace {

// dataset.reference (any scalar or a list) and dataset.neighbors (a list or auto).
TEST(ListOrScalar, ScalarsListsAndTheirEffectiveYaml) {
  std::vector<std::string> references{"0005"}, neighbors;
  Schema schema;
  schema.AddListOrScalar("dataset.reference", &references, {}, {"reference"});
  schema.AddListOrScalar("dataset.neighbors", &neighbors, {"auto"}, {"neighbours"});
  schema.LoadString("dataset:\n  reference: 0007\n  neighbors: auto\n", "test.yaml");
  EXPECT_EQ(references, std::vector<std::string>{"0007"});
  EXPECT_EQ(neighbors, std::vector<std::string>{"auto"});
  EXPECT_NE(schema.ToYaml().find("reference: 0007"), std::string::npos) << schema.ToYaml();
  EXPECT_NE(schema.ToYaml().find("neighbors: auto"), std::string::npos) << schema.ToYaml();
  schema.ApplyOverride("dataset.reference=[0003, 0004]");
  schema.ApplyOverride("dataset.neighbors=[im1]");
  EXPECT_EQ(references, (std::vector<std::string>{"0003", "0004"}));
  EXPECT_EQ(neighbors, std::vector<std::string>{"im1"});
  // A one-element list that is not one of the scalar words stays a list.
  EXPECT_NE(schema.ToYaml().find("neighbors: [im1]"), std::string::npos) << schema.ToYaml();
  EXPECT_NE(schema.ToYaml().find("reference: [0003, 0004]"), std::string::npos) << schema.ToYaml();
  try {
    schema.ApplyOverride("dataset.neighbors=im2");
    FAIL() << "a scalar other than auto was accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(
        std::string(e.what()).find("dataset.neighbors = im2. Violated constraint: a list or auto"),
        std::string::npos)
        << e.what();
  }
  EXPECT_EQ(neighbors, std::vector<std::string>{"im1"});  // unchanged by the failed override
}

}  // namespace
}  // namespace gcpstereo::config
