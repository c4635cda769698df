// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace gcpstereo::config {

// A closed or open numeric interval that a configuration value must lie in.
struct Range {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_inclusive = true;
  bool max_inclusive = true;

  static Range Any() { return {}; }
  // Finite values >= v (or > v); infinity is excluded.
  static Range AtLeast(double v) {
    return {v, std::numeric_limits<double>::infinity(), true, false};
  }
  static Range GreaterThan(double v) {
    return {v, std::numeric_limits<double>::infinity(), false, false};
  }
  // Values > v, infinity included (e.g. a maximum depth that may be unbounded: .inf in YAML).
  static Range GreaterThanOrInfinite(double v) {
    return {v, std::numeric_limits<double>::infinity(), false, true};
  }
  static Range Between(double lo, double hi) { return {lo, hi, true, true}; }
  // [lo, hi)
  static Range HalfOpen(double lo, double hi) { return {lo, hi, true, false}; }

  bool Contains(double v) const;
  // "x >= 0", "0 <= x < 1", … with `name` as x.
  std::string Describe(const std::string& name) const;
};

// Documentation attached to a key: what it means, its unit and its symbol in the paper.
struct KeyDoc {
  std::string text;
  std::string unit;    // "px", "m", "RGB grey levels", "" when dimensionless
  std::string symbol;  // the paper's symbol (λs, γc …), "" if none
};

// A typed configuration schema bound to the fields of options structs.
//
// Each key ("optimizer.lambda_s") is registered with a pointer to the field it sets, its valid
// range or choices and its documentation; the field's current value is its default. Loading a YAML
// file walks the document: an unknown key, a value of the wrong type or out of range throws a
// ConfigError "<file>:<line>: <key> = <value>. Violated constraint: <bound>"; a quoted scalar that
// does not close on the line where it starts (multi-line quoted scalars are refused) throws
// "<file>:<line>: the quoted value of <key> is not closed on its line …". `--set KEY=VALUE`
// overrides go through the same checks. The schema then writes the effective configuration.
class Schema {
 public:
  Schema();
  ~Schema();
  Schema(const Schema&) = delete;
  Schema& operator=(const Schema&) = delete;

  void Add(const std::string& key, double* field, Range range, KeyDoc doc);
  void Add(const std::string& key, int* field, Range range, KeyDoc doc);
  void Add(const std::string& key, bool* field, KeyDoc doc);
  // `choices` empty = any string (e.g. a path).
  void Add(const std::string& key, std::string* field, std::vector<std::string> choices,
           KeyDoc doc);
  // A list of strings, each one of `choices` (or any when empty).
  void Add(const std::string& key, std::vector<std::string>* field,
           std::vector<std::string> choices, KeyDoc doc);
  // A list of strings that may also be written as one scalar: any scalar when `scalars` is empty
  // (`dataset.reference: 0005` = [0005]), else only one of `scalars` (`dataset.neighbors: auto`).
  // The effective configuration writes a one-element list of that kind back as the scalar.
  void AddListOrScalar(const std::string& key, std::vector<std::string>* field,
                       std::vector<std::string> scalars, KeyDoc doc);
  // A list of integers; `fixed_size` > 0 requires exactly that many elements.
  void Add(const std::string& key, std::vector<int>* field, std::size_t fixed_size, Range range,
           KeyDoc doc);
  // A number that may be omitted (null, "auto" or absent = std::nullopt).
  void Add(const std::string& key, std::optional<double>* field, Range range, KeyDoc doc);
  // An integer that may be omitted (null, "auto" or absent = std::nullopt).
  void Add(const std::string& key, std::optional<int>* field, Range range, KeyDoc doc);

  // Applies a YAML file / text on top of the current values. `source` names it in errors.
  void LoadFile(const std::string& path);
  void LoadString(const std::string& yaml_text, const std::string& source);
  // Applies one "KEY=VALUE" override; VALUE is parsed as YAML ("[im1, im3]" is a list).
  void ApplyOverride(const std::string& assignment);

  // Registered keys, in registration order.
  std::vector<std::string> Keys() const;
  bool HasKey(const std::string& key) const;
  // Keys whose value came from a file or an override (not the default).
  bool IsSet(const std::string& key) const;

  // The effective configuration as YAML: every key with its current value, nested by section,
  // each with its documentation as a comment.
  std::string ToYaml() const;
  // A human-readable table of all keys: key, type, default, range, unit, symbol, meaning.
  std::string Describe() const;

  struct Entry;

 private:
  void Register(std::unique_ptr<Entry> entry);

  std::vector<std::unique_ptr<Entry>> entries_;
  std::map<std::string, Entry*> by_key_;
};

}  // namespace gcpstereo::config
