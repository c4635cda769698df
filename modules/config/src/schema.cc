// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/config/schema.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iomanip>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <variant>

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include "gcpstereo/core/error.h"

namespace gcpstereo::config {
namespace {

std::string FormatNumber(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  std::ostringstream s;
  s << std::setprecision(10) << v;
  return s.str();
}

// The scalar text of a node for messages (a compact flow dump for collections).
// The shortest decimal text that reads back as exactly `value` ("0.1", not yaml-cpp's
// "0.10000000000000001"), so that `gcpstereo keys` and effective_config.yaml stay legible and
// still reload to the same bits.
YAML::Node ShortestNumberNode(double value) {
  if (!std::isfinite(value)) return YAML::Node(value);
  char text[40];
  for (int precision = 6; precision <= 17; ++precision) {
    std::snprintf(text, sizeof(text), "%.*g", precision, value);
    if (std::strtod(text, nullptr) == value) break;
  }
  return YAML::Node(std::string(text));
}

std::string NodeText(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "null";
  if (node.IsScalar()) return node.Scalar();
  YAML::Emitter out;
  out << YAML::Flow << node;
  return out.c_str();
}

size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      cur[j] =
          std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

std::string Join(const std::vector<std::string>& items, const std::string& sep) {
  std::string out;
  for (size_t i = 0; i < items.size(); ++i) out += (i ? sep : "") + items[i];
  return out;
}

}  // namespace

bool Range::Contains(double v) const {
  if (std::isnan(v)) return false;
  const bool lo_ok = min_inclusive ? v >= min : v > min;
  const bool hi_ok = max_inclusive ? v <= max : v < max;
  return lo_ok && hi_ok;
}

std::string Range::Describe(const std::string& name) const {
  const bool has_lo = std::isfinite(min), has_hi = std::isfinite(max);
  if (has_lo && has_hi) {
    return FormatNumber(min) + (min_inclusive ? " <= " : " < ") + name +
           (max_inclusive ? " <= " : " < ") + FormatNumber(max);
  }
  if (has_lo) return name + (min_inclusive ? " >= " : " > ") + FormatNumber(min);
  if (has_hi) return name + (max_inclusive ? " <= " : " < ") + FormatNumber(max);
  return name + " finite";
}

// One registered key.
struct Schema::Entry {
  using Target = std::variant<double*, int*, bool*, std::string*, std::vector<std::string>*,
                              std::vector<int>*, std::optional<double>*, std::optional<int>*>;
  std::string key;
  Target target;
  Range range;
  std::vector<std::string> choices;
  std::size_t fixed_size = 0;
  // List-or-scalar string lists (AddListOrScalar): a scalar is accepted as a one-element list.
  bool scalar_allowed = false;
  std::vector<std::string> scalar_words;  // empty: any scalar
  KeyDoc doc;

  bool WritesAsScalar(const std::vector<std::string>& list) const {
    return scalar_allowed && list.size() == 1 &&
           (scalar_words.empty() || std::find(scalar_words.begin(), scalar_words.end(),
                                              list.front()) != scalar_words.end());
  }
  std::string default_text;
  bool set = false;

  std::string TypeName() const {
    switch (target.index()) {
      case 0:
        return "number";
      case 1:
        return "integer";
      case 2:
        return "bool";
      case 3:
        return choices.empty() ? "string" : "one of {" + Join(choices, ", ") + "}";
      case 4:
        if (scalar_allowed) {
          return scalar_words.empty() ? "string or list of strings"
                                      : "list of strings or " + Join(scalar_words, ", ");
        }
        return "list of " +
               (choices.empty() ? std::string("strings") : "{" + Join(choices, ", ") + "}");
      case 5:
        return fixed_size ? "list of " + std::to_string(fixed_size) + " integers"
                          : "list of integers";
      case 6:
        return "number or auto";
      case 7:
        return "integer or auto";
    }
    return "?";
  }

  YAML::Node ValueNode() const {
    YAML::Node n;
    std::visit(
        [&](auto* p) {
          using T = std::decay_t<decltype(*p)>;
          if constexpr (std::is_same_v<T, std::optional<double>>) {
            n = *p ? ShortestNumberNode(**p) : YAML::Node("auto");
          } else if constexpr (std::is_same_v<T, std::optional<int>>) {
            n = *p ? YAML::Node(**p) : YAML::Node("auto");
          } else if constexpr (std::is_same_v<T, std::vector<std::string>>) {
            if (WritesAsScalar(*p)) {
              n = p->front();
            } else {
              n = YAML::Node(YAML::NodeType::Sequence);
              for (const auto& v : *p) n.push_back(v);
              n.SetStyle(YAML::EmitterStyle::Flow);
            }
          } else if constexpr (std::is_same_v<T, std::vector<int>>) {
            n = YAML::Node(YAML::NodeType::Sequence);
            for (const auto& v : *p) n.push_back(v);
            n.SetStyle(YAML::EmitterStyle::Flow);
          } else if constexpr (std::is_same_v<T, double>) {
            n = ShortestNumberNode(*p);
          } else {
            n = *p;
          }
        },
        target);
    return n;
  }

  std::string ValueText() const { return NodeText(ValueNode()); }
};

Schema::Schema() = default;
Schema::~Schema() = default;

void Schema::Register(std::unique_ptr<Entry> entry) {
  if (by_key_.count(entry->key)) throw Error("configuration key registered twice: " + entry->key);
  entry->default_text = entry->ValueText();
  by_key_[entry->key] = entry.get();
  entries_.push_back(std::move(entry));
}

#define GCPSTEREO_ADD_ENTRY(...)      \
  auto e = std::make_unique<Entry>(); \
  e->key = key;                       \
  e->target = field;                  \
  e->doc = std::move(doc);            \
  __VA_ARGS__;                        \
  Register(std::move(e));

void Schema::Add(const std::string& key, double* field, Range range, KeyDoc doc) {
  GCPSTEREO_ADD_ENTRY(e->range = range)
}
void Schema::Add(const std::string& key, int* field, Range range, KeyDoc doc) {
  GCPSTEREO_ADD_ENTRY(e->range = range)
}
void Schema::Add(const std::string& key, bool* field, KeyDoc doc) { GCPSTEREO_ADD_ENTRY() }
void Schema::Add(const std::string& key, std::string* field, std::vector<std::string> choices,
                 KeyDoc doc) {
  GCPSTEREO_ADD_ENTRY(e->choices = std::move(choices))
}
void Schema::Add(const std::string& key, std::vector<std::string>* field,
                 std::vector<std::string> choices, KeyDoc doc) {
  GCPSTEREO_ADD_ENTRY(e->choices = std::move(choices))
}
void Schema::AddListOrScalar(const std::string& key, std::vector<std::string>* field,
                             std::vector<std::string> scalars, KeyDoc doc) {
  GCPSTEREO_ADD_ENTRY(e->scalar_allowed = true; e->scalar_words = std::move(scalars))
}
void Schema::Add(const std::string& key, std::vector<int>* field, std::size_t fixed_size,
                 Range range, KeyDoc doc) {
  GCPSTEREO_ADD_ENTRY(e->fixed_size = fixed_size; e->range = range)
}
void Schema::Add(const std::string& key, std::optional<double>* field, Range range, KeyDoc doc) {
  GCPSTEREO_ADD_ENTRY(e->range = range)
}
void Schema::Add(const std::string& key, std::optional<int>* field, Range range, KeyDoc doc) {
  GCPSTEREO_ADD_ENTRY(e->range = range)
}
#undef GCPSTEREO_ADD_ENTRY

namespace {

// Parses and checks one value; `where` is "<source>:<line>" for messages.
class ValueApplier {
 public:
  ValueApplier(const Schema::Entry& entry, const YAML::Node& node, std::string where)
      : entry_(entry), node_(node), where_(std::move(where)) {}

  [[noreturn]] void Fail(const std::string& constraint) const {
    throw ConfigError(where_ + ": " + ViolatedConstraint(entry_.key, NodeText(node_), constraint));
  }

  double Number(const YAML::Node& n) const {
    if (!n.IsScalar()) Fail("a number");
    double v;
    if (!YAML::convert<double>::decode(n, v) || std::isnan(v)) Fail("a number");
    if (std::isinf(v) && !entry_.range.Contains(v)) Fail("a finite number");
    return v;
  }
  int Integer(const YAML::Node& n) const {
    if (!n.IsScalar()) Fail("an integer");
    int v;
    if (!YAML::convert<int>::decode(n, v)) Fail("an integer");
    return v;
  }
  void CheckRange(double v) const {
    if (!entry_.range.Contains(v)) Fail(entry_.range.Describe(entry_.key));
  }
  std::string Choice(const YAML::Node& n) const {
    if (!n.IsScalar()) Fail("a string");
    const std::string& s = n.Scalar();
    if (!entry_.choices.empty() &&
        std::find(entry_.choices.begin(), entry_.choices.end(), s) == entry_.choices.end()) {
      Fail("one of " + Join(entry_.choices, ", "));
    }
    return s;
  }

  // Parses everything first, then assigns, so a failed value leaves the field untouched.
  void Apply(const Schema::Entry::Target& target) const {
    std::visit([&](auto* p) { Assign(p); }, target);
  }

 private:
  void Assign(double* p) const {
    const double v = Number(node_);
    CheckRange(v);
    *p = v;
  }
  void Assign(int* p) const {
    const int v = Integer(node_);
    CheckRange(v);
    *p = v;
  }
  void Assign(bool* p) const {
    bool v;
    if (!node_.IsScalar() || !YAML::convert<bool>::decode(node_, v)) Fail("true or false");
    *p = v;
  }
  void Assign(std::string* p) const { *p = Choice(node_); }
  void Assign(std::vector<std::string>* p) const {
    std::vector<std::string> out;
    if (node_.IsNull()) {
      *p = out;
      return;
    }
    if (node_.IsScalar() && entry_.scalar_allowed) {
      const std::string& word = node_.Scalar();
      if (!entry_.scalar_words.empty() &&
          std::find(entry_.scalar_words.begin(), entry_.scalar_words.end(), word) ==
              entry_.scalar_words.end()) {
        Fail("a list or " + Join(entry_.scalar_words, ", "));
      }
      *p = {word};
      return;
    }
    if (!node_.IsSequence()) Fail("a list");
    for (const auto& item : node_) out.push_back(Choice(item));
    *p = out;
  }
  void Assign(std::vector<int>* p) const {
    if (!node_.IsSequence()) Fail(entry_.TypeName());
    std::vector<int> out;
    for (const auto& item : node_) {
      const int v = Integer(item);
      CheckRange(v);
      out.push_back(v);
    }
    if (entry_.fixed_size && out.size() != entry_.fixed_size) Fail(entry_.TypeName());
    *p = out;
  }
  void Assign(std::optional<double>* p) const {
    if (node_.IsNull() || (node_.IsScalar() && node_.Scalar() == "auto")) {
      p->reset();
      return;
    }
    double v = 0.0;
    if (!node_.IsScalar() || !YAML::convert<double>::decode(node_, v) || std::isnan(v)) {
      Fail("a number or auto");
    }
    if (std::isinf(v) && !entry_.range.Contains(v)) Fail("a finite number or auto");
    CheckRange(v);
    *p = v;
  }
  void Assign(std::optional<int>* p) const {
    if (node_.IsNull() || (node_.IsScalar() && node_.Scalar() == "auto")) {
      p->reset();
      return;
    }
    int v = 0;
    if (!node_.IsScalar() || !YAML::convert<int>::decode(node_, v)) Fail("an integer or auto");
    CheckRange(v);
    *p = v;
  }

  const Schema::Entry& entry_;
  const YAML::Node& node_;
  std::string where_;
};

std::string Where(const std::string& source, const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  if (mark.line < 0) return source;
  return source + ":" + std::to_string(mark.line + 1);
}

}  // namespace

namespace {

struct Walker {
  const std::map<std::string, Schema::Entry*>& by_key;
  const std::string& source;
  std::map<std::string, YAML::Mark>* seen;  // keys applied so far, where

  bool IsSection(const std::string& prefix) const {
    auto it = by_key.lower_bound(prefix + ".");
    return it != by_key.end() && it->first.compare(0, prefix.size() + 1, prefix + ".") == 0;
  }

  std::string Suggestion(const std::string& key) const {
    std::string best;
    size_t best_distance = 4;
    for (const auto& [k, e] : by_key) {
      const size_t d = EditDistance(key, k);
      if (d < best_distance) best_distance = d, best = k;
    }
    return best.empty() ? "" : " (did you mean '" + best + "'?)";
  }

  void Walk(const YAML::Node& map, const std::string& prefix) const {
    for (const auto& kv : map) {
      const std::string name = kv.first.as<std::string>();
      const std::string key = prefix.empty() ? name : prefix + "." + name;
      const YAML::Node& value = kv.second;
      auto it = by_key.find(key);
      if (it != by_key.end()) {
        // A key given twice (YAML would let the later one win silently): which did the user
        // mean? Sections may repeat (effective_config.yaml groups keys that way); keys may not.
        const auto [first, fresh] = seen->emplace(key, kv.first.Mark());
        if (!fresh) {
          throw ConfigError(Where(source, kv.first) + ": " + key +
                            " is given twice (first on line " +
                            std::to_string(first->second.line + 1) + ")");
        }
        ValueApplier(*it->second, value, Where(source, kv.first)).Apply(it->second->target);
        it->second->set = true;
      } else if (IsSection(key)) {
        if (value.IsNull()) continue;  // an empty section keeps its defaults
        if (!value.IsMap()) {
          throw ConfigError(Where(source, kv.first) + ": " + key +
                            " is a section: expected a mapping of keys, got '" + NodeText(value) +
                            "'");
        }
        Walk(value, key);
      } else {
        throw ConfigError(Where(source, kv.first) + ": unknown configuration key '" + key + "'" +
                          Suggestion(key));
      }
    }
  }
};

// yaml-cpp (0.7) lets a quoted scalar whose closing quote is missing run on over the lines that
// follow, up to the next quote of its kind or the end of the text: `reference: "0005` swallows
// every later key, and the user reads a misleading error (dataset.reference is required, a view
// name of five lines, a syntax error further down) or none at all. Our configurations never need
// a quoted scalar over several lines, so one (key or value) whose closing quote is not on the line
// where it starts is refused here, naming that line and the key. The text is read event by event:
// the scalar's event comes before any syntax error its folding causes further down, so it is found
// then too; a syntax error before it is left to YAML::Load, which reports it.
struct UnclosedQuote {
  int line = 0;     // 0-based, as YAML::Mark
  std::string key;  // the dotted key of the value, or of the section of a key ("" at the top)
  char quote = '"';

  // Keys are not told apart from values: yaml-cpp may take a run-on scalar for either (in a flow
  // list it makes "lidar] …" the key of a one-pair map), and the section names the place anyway.
  std::string Describe() const {
    return (key.empty() ? std::string("a quoted string") : "the quoted value of " + key) +
           " is not closed on its line (missing closing " + quote + ")";
  }
};

class UnclosedQuoteFinder : public YAML::EventHandler {
 public:
  // `key` prefixes the keys found (the key of a --set value; "" for a file).
  UnclosedQuoteFinder(const std::string& text, std::string key) : prefix_(std::move(key)) {
    // yaml-cpp's marks count from after a UTF-8 byte-order mark, in bytes.
    std::stringstream in(text.compare(0, 3, "\xEF\xBB\xBF") == 0 ? text.substr(3) : text);
    for (std::string line; std::getline(in, line);) lines_.push_back(line);
  }

  const std::optional<UnclosedQuote>& found() const { return found_; }

  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override { NodeDone(nullptr); }
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override { NodeDone(nullptr); }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                const std::string& value) override {
    char quote = 0;
    if (!found_ && !EndsOnItsLine(mark, &quote)) {
      found_ = UnclosedQuote{mark.line, KeyHere(), quote};
    }
    NodeDone(&value);
  }
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {
    stack_.push_back({false, KeyHere()});
  }
  void OnSequenceEnd() override { EndCollection(); }
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {
    stack_.push_back({true, KeyHere()});
  }
  void OnMapEnd() override { EndCollection(); }

 private:
  struct Collection {
    bool is_map;
    std::string key;     // dotted key of the collection
    bool at_key = true;  // maps: the next node is a key (else the value of `last_key`)
    std::string last_key;
  };

  // The dotted key the next node belongs to (a list item: the list's key).
  std::string KeyHere() const {
    if (stack_.empty()) return prefix_;
    const Collection& c = stack_.back();
    if (!c.is_map || c.at_key) return c.key;  // a list item, a key
    return c.key.empty() ? c.last_key : c.key + "." + c.last_key;
  }

  void NodeDone(const std::string* scalar) {
    if (stack_.empty() || !stack_.back().is_map) return;
    Collection& c = stack_.back();
    if (c.at_key) c.last_key = scalar ? *scalar : "?";
    c.at_key = !c.at_key;
  }

  void EndCollection() {
    stack_.pop_back();
    NodeDone(nullptr);
  }

  // Whether the scalar starting at `mark` closes on that line. Plain and block scalars (and
  // a tag or anchor alone on its line) do not start with a quote there and count as closed.
  // `quote` receives the quote character.
  bool EndsOnItsLine(const YAML::Mark& mark, char* quote) const {
    if (mark.line < 0 || mark.line >= static_cast<int>(lines_.size())) return true;
    const std::string& line = lines_[mark.line];
    size_t i = static_cast<size_t>(std::max(mark.column, 0));
    // The node's mark is at its properties (`!!str "x"`, `&a 'x'`) when it has some.
    while (i < line.size() && (line[i] == '!' || line[i] == '&')) {
      while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
      while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    }
    if (i >= line.size() || (line[i] != '"' && line[i] != '\'')) return true;
    *quote = line[i];
    for (++i; i < line.size(); ++i) {
      if (*quote == '"' && line[i] == '\\') {
        ++i;  // an escape: \" is not the end (a \ at the line's end continues the scalar)
      } else if (*quote == '\'' && line[i] == '\'' && i + 1 < line.size() && line[i + 1] == '\'') {
        ++i;  // '' is a quote inside single quotes
      } else if (line[i] == *quote) {
        return true;
      }
    }
    return false;
  }

  std::string prefix_;
  std::vector<std::string> lines_;
  std::vector<Collection> stack_;
  std::optional<UnclosedQuote> found_;
};

std::optional<UnclosedQuote> FindUnclosedQuote(const std::string& yaml_text,
                                               const std::string& key) {
  UnclosedQuoteFinder finder(yaml_text, key);
  // yaml-cpp fails at "illegal EOF in scalar" (no mark of the scalar) when the text ends inside the
  // quotes without a newline; with one it reports the run-on scalar.
  std::stringstream in(yaml_text + "\n");
  try {
    YAML::Parser parser(in);
    parser.HandleNextDocument(finder);
  } catch (const YAML::Exception&) {
    // A syntax error: reported by YAML::Load, unless a run-on quoted scalar came first.
  }
  return finder.found();
}

}  // namespace

void Schema::LoadString(const std::string& yaml_text, const std::string& source) {
  if (const std::optional<UnclosedQuote> unclosed = FindUnclosedQuote(yaml_text, "")) {
    throw ConfigError(source + ":" + std::to_string(unclosed->line + 1) + ": " +
                      unclosed->Describe());
  }
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(source + ":" + std::to_string(e.mark.line + 1) +
                      ": YAML syntax error: " + e.msg);
  }
  if (root.IsNull()) return;  // an empty file keeps every default
  if (!root.IsMap()) throw ConfigError(source + ": the configuration must be a mapping of keys");
  std::map<std::string, YAML::Mark> seen;
  Walker{by_key_, source, &seen}.Walk(root, "");
}

void Schema::LoadFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw IoError(path, "cannot open configuration file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  LoadString(buffer.str(), path);
}

void Schema::ApplyOverride(const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw ConfigError("--set " + assignment + ": expected KEY=VALUE");
  }
  const std::string key = assignment.substr(0, eq);
  const std::string value_text = assignment.substr(eq + 1);
  auto it = by_key_.find(key);
  if (it == by_key_.end()) {
    throw ConfigError("--set " + assignment + ": unknown configuration key '" + key + "'" +
                      Walker{by_key_, key}.Suggestion(key));
  }
  // A --set value is one line as a rule; one whose quote does not close there is refused as in a
  // file (LoadString).
  if (const std::optional<UnclosedQuote> unclosed = FindUnclosedQuote(value_text, key)) {
    throw ConfigError("--set " + assignment + ": " + unclosed->Describe());
  }
  YAML::Node value;
  try {
    value = YAML::Load(value_text);
  } catch (const YAML::Exception& e) {
    throw ConfigError("--set " + assignment + ": cannot parse the value as YAML: " + e.msg);
  }
  ValueApplier(*it->second, value, "--set").Apply(it->second->target);
  it->second->set = true;
}

std::vector<std::string> Schema::Keys() const {
  std::vector<std::string> keys;
  for (const auto& e : entries_) keys.push_back(e->key);
  return keys;
}

bool Schema::HasKey(const std::string& key) const { return by_key_.count(key) > 0; }

bool Schema::IsSet(const std::string& key) const {
  auto it = by_key_.find(key);
  return it != by_key_.end() && it->second->set;
}

std::string Schema::ToYaml() const {
  // Emit sections in registration order; each key carries its documentation as a comment.
  YAML::Emitter out;
  out << YAML::BeginMap;
  std::vector<std::string> open;  // the current section path
  for (const auto& e : entries_) {
    std::vector<std::string> parts;
    std::stringstream ss(e->key);
    for (std::string part; std::getline(ss, part, '.');) parts.push_back(part);
    const std::vector<std::string> section(parts.begin(), parts.end() - 1);
    size_t common = 0;
    while (common < open.size() && common < section.size() && open[common] == section[common]) {
      ++common;
    }
    for (size_t i = open.size(); i > common; --i) out << YAML::EndMap;
    for (size_t i = common; i < section.size(); ++i) {
      out << YAML::Key << section[i] << YAML::Value << YAML::BeginMap;
    }
    open = section;
    std::string comment = e->doc.text;
    if (!e->doc.unit.empty()) comment += " [" + e->doc.unit + "]";
    if (!e->doc.symbol.empty()) comment += " (paper: " + e->doc.symbol + ")";
    out << YAML::Key << parts.back() << YAML::Value << e->ValueNode();
    if (!comment.empty()) out << YAML::Comment(comment);
  }
  for (size_t i = 0; i < open.size(); ++i) out << YAML::EndMap;
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

std::string Schema::Describe() const {
  std::ostringstream s;
  for (const auto& e : entries_) {
    s << "  " << e->key << "  (" << e->TypeName() << ", default " << e->default_text;
    if (e->target.index() <= 1 || e->target.index() >= 5) {
      if (std::isfinite(e->range.min) || std::isfinite(e->range.max)) {
        s << ", " << e->range.Describe("x");
      }
    }
    if (!e->doc.unit.empty()) s << ", unit " << e->doc.unit;
    if (!e->doc.symbol.empty()) s << ", paper " << e->doc.symbol;
    s << ")\n      " << e->doc.text << "\n";
  }
  return s.str();
}

}  // namespace gcpstereo::config
