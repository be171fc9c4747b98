// Located YAML reading (see yaml_reader.hpp).
#include "afhub/yaml/yaml_reader.hpp"

#include <yaml-cpp/eventhandler.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/limits.hpp"
#include "afhub/yaml/input_file.hpp"

namespace afhub::yaml {

const char* kind_of(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Map:
      return "a map";
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Scalar:
      return "a value";
    default:
      return "nothing";
  }
}

namespace {

// A file's cost read from the parser's events, without building its tree: its nodes
// (an alias counts the nodes it repeats, as every reader walks them again) and how
// deep its lists and maps nest. Throws at the first node past a bound, naming it.
class CostScan : public YAML::EventHandler {
 public:
  explicit CostScan(const std::string& path) : path_(path) {}

  void OnDocumentStart(const YAML::Mark& mark) override { start_ = mark; }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t anchor) override { leaf(mark, anchor); }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                const std::string&) override {
    holds_something_ = true;
    leaf(mark, anchor);
  }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    const std::size_t size = anchor < anchored_.size() ? anchored_[anchor] : 1;
    if (size == kOpen)
      refuse(mark,
             "this alias names a list or map that contains it, which would repeat "
             "without end; write the repeated part out");
    holds_something_ = true;
    add(mark, size);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                       YAML::EmitterStyle::value) override {
    open(mark, anchor);
  }
  void OnSequenceEnd() override { close(); }
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                  YAML::EmitterStyle::value) override {
    open(mark, anchor);
  }
  void OnMapEnd() override { close(); }

  // Where the document began, and whether it holds more than a null.
  const YAML::Mark& start() const { return start_; }
  bool holds_something() const { return holds_something_ || nodes_ > 1; }

 private:
  static constexpr std::size_t kOpen = 0;  // an anchored node not yet ended

  struct Opened {
    std::size_t nodes_before;
    YAML::anchor_t anchor;
  };

  [[noreturn]] void refuse(const YAML::Mark& mark, const std::string& what) const {
    throw Error(path_ + ":" + std::to_string(mark.line + 1) + ":" +
                std::to_string(mark.column + 1) + ": error: " + what);
  }
  void add(const YAML::Mark& mark, std::size_t count) {
    if (count > kMaxYamlNodes - nodes_)
      refuse(mark, "the file has more than " + std::to_string(kMaxYamlNodes) +
                       " values, lists and maps by here; afhub reads at most that many per file "
                       "(kMaxYamlNodes), and real models have a few thousand: is it the right "
                       "file? Split a generated model into several files");
    nodes_ += count;
  }
  void note(YAML::anchor_t anchor, std::size_t size) {
    if (anchor == YAML::NullAnchor) return;
    if (anchored_.size() <= anchor) anchored_.resize(anchor + 1, 1);
    anchored_[anchor] = size;
  }
  void leaf(const YAML::Mark& mark, YAML::anchor_t anchor) {
    add(mark, 1);
    note(anchor, 1);
  }
  void open(const YAML::Mark& mark, YAML::anchor_t anchor) {
    if (opened_.size() == kMaxYamlDepth)
      refuse(mark, "lists and maps nest more than " + std::to_string(kMaxYamlDepth) +
                       " deep here; afhub reads at most that many levels (kMaxYamlDepth), and "
                       "real models nest 5: is it the right file?");
    add(mark, 1);
    opened_.push_back({nodes_ - 1, anchor});
    note(anchor, kOpen);
  }
  void close() {
    const Opened done = opened_.back();
    opened_.pop_back();
    note(done.anchor, nodes_ - done.nodes_before);
  }

  const std::string& path_;
  YAML::Mark start_;
  bool holds_something_ = false;
  std::size_t nodes_ = 0;
  std::vector<Opened> opened_;
  std::vector<std::size_t> anchored_;  // by anchor: its node's size, kOpen until it ends
};

}  // namespace

YAML::Node parse(const std::string& path, const std::string& text) {
  try {
    std::istringstream stream(text);
    YAML::Parser parser(stream);
    CostScan cost(path);
    parser.HandleNextDocument(cost);
    // yaml-cpp reads the first document: a second one would go unread.
    if (CostScan second(path); parser.HandleNextDocument(second) && second.holds_something())
      throw Error(path + ":" + std::to_string(second.start().line + 1) +
                  ": error: a second YAML document begins here; afhub reads one document per "
                  "file: put this one in a file of its own");
    return YAML::Load(text);
  } catch (const YAML::ParserException& error) {
    throw Error(path + ":" + std::to_string(error.mark.line + 1) + ":" +
                std::to_string(error.mark.column + 1) + ": error: YAML syntax: " + error.msg);
  } catch (const YAML::Exception& error) {
    throw Error(path + ": error: YAML: " + error.msg);
  }
}

YAML::Node load_map(const std::string& path, const std::string& what) {
  const YAML::Node root = parse(path, read_input_file(path, kMaxYamlFileBytes, what));
  if (root.IsNull())
    throw Error(path + ":1:1: error: the file holds nothing (empty, or comments only); expected " +
                what);
  if (!root.IsMap()) throw Error(path + ":1:1: error: expected " + what + ", not " + kind_of(root));
  return root;
}

std::string Reader::where(const YAML::Node& node) const {
  const YAML::Mark mark = node.Mark();
  return path_ + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
}

void Reader::fail(const YAML::Node& node, const std::string& what) const {
  throw Error(where(node) + ": error: " + what);
}

void Reader::warn(const YAML::Node& node, const std::string& what) const {
  if (!warnings_) fail(node, what);
  warnings_->push_back(where(node) + ": warning: " + what);
}

void Reader::check_keys(const YAML::Node& map, const std::set<std::string>& known,
                        const std::string& owner) const {
  std::set<std::string> seen;
  for (const auto& entry : map) {
    const std::string key = entry.first.Scalar();
    if (!seen.insert(key).second)
      fail(entry.first, "'" + key + "' is written twice in " + owner +
                            ": which one is meant would be a guess; keep one");
    if (!known.count(key))
      warn(entry.first, "unknown key '" + key + "' in " + owner + " is ignored");
  }
}

double Reader::finite(const YAML::Node& node, const std::string& what) const {
  if (!node.IsScalar()) fail(node, "'" + what + "' must be a number, not " + kind_of(node));
  double value = 0.0;
  if (!YAML::convert<double>::decode(node, value))
    fail(node, "'" + what + "' must be a number, got '" + node.Scalar() + "'");
  if (!std::isfinite(value))
    fail(node, "'" + what + "' must be finite, got '" + node.Scalar() + "'");
  return value;
}

double Reader::number(const YAML::Node& node, const std::string& what) const {
  const double value = finite(node, what);
  if (std::abs(value) > kMaxMagnitude)
    fail(node, "'" + what + "' is " + node.Scalar() + ", beyond any physical value (at most " +
                   number_text(kMaxMagnitude) + " in magnitude)");
  return value;
}

double Reader::in_range(const YAML::Node& node, const std::string& what, double low,
                        double high) const {
  const double value = finite(node, what);
  if (value < low || value > high)
    fail(node, "'" + what + "' is " + node.Scalar() + "; write a value from " + number_text(low) +
                   " to " + number_text(high));
  return value;
}

double Reader::non_negative(const YAML::Node& node, const std::string& what) const {
  const double value = number(node, what);
  if (value < 0.0) fail(node, "'" + what + "' must not be negative, got " + node.Scalar());
  return value;
}

double Reader::positive(const YAML::Node& node, const std::string& what) const {
  const double value = number(node, what);
  if (value <= 0.0) fail(node, "'" + what + "' must be positive, got " + node.Scalar());
  return value;
}

bool Reader::flag(const YAML::Node& node, const std::string& what) const {
  bool value = false;
  if (!node.IsScalar() || !YAML::convert<bool>::decode(node, value))
    fail(node, "'" + what + "' must be true or false");
  return value;
}

std::string Reader::text(const YAML::Node& node, const std::string& what) const {
  if (!node.IsScalar()) fail(node, "'" + what + "' must be text, not " + kind_of(node));
  return node.Scalar();
}

void Reader::require_map(const YAML::Node& node, const std::string& what,
                         const std::string& example) const {
  if (!node.IsMap())
    fail(node, "'" + what + "' must be a map such as " + example + ", not " + kind_of(node));
}

MapIndex::MapIndex(const Reader& reader, const YAML::Node& map) {
  for (const auto& entry : map) {
    const YAML::Node& key = entry.first;
    if (!key.IsScalar()) continue;  // no name to look it up by
    auto [found, added] = entries_.try_emplace(key.Scalar(), Entry{key, entry.second});
    if (!added)
      reader.fail(key, "'" + key.Scalar() + "' is written twice in this map (first at " +
                           reader.where(found->second.key) + "); keep one");
  }
}

const YAML::Node* MapIndex::find(const std::string& key) const {
  auto found = entries_.find(key);
  return found == entries_.end() ? nullptr : &found->second.value;
}

}  // namespace afhub::yaml
