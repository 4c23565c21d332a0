#include <mpm/core/config.h>
#include <mpm/core/number_text.h>

#include <mpm/core/error.h>

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace mpm {

namespace {

constexpr double kUnbounded = 1e308;

std::string join(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }

std::string yaml_text(const YAML::Node& node) {
  if (node.IsScalar()) return node.Scalar();
  if (!node.IsDefined() || node.IsNull()) return "null";
  YAML::Emitter out;
  out << YAML::Flow << node;
  return out.c_str();
}

//! What a value is when it is not the scalar a getter wanted (", got a map"); empty for scalars.
std::string got(const YAML::Node& node) {
  if (node.IsMap()) return ", got a map";
  if (node.IsSequence()) return ", got a list";
  if (node.IsNull()) return ", got nothing";
  return "";
}

//! The double a plain scalar spells (YAML ".inf"/".nan" included); std::nullopt for no number.
std::optional<double> to_number(const YAML::Node& node) {
  if (!node.IsScalar()) return std::nullopt;
  std::string text = node.Scalar();
  if (!text.empty() && text.front() == '+') text.erase(0, 1);
  std::string lower = text;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
  if (lower == ".inf" || lower == "-.inf") return lower.front() == '-' ? -HUGE_VAL : HUGE_VAL;
  if (lower == ".nan") return std::nan("");
  double value = 0.0;
  const auto result = std::from_chars(text.data(), text.data() + text.size(), value);
  if (result.ec != std::errc() || result.ptr != text.data() + text.size()) return std::nullopt;
  return value;
}

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

//! The value node of `key` in `map`, or an undefined node when absent.
YAML::Node lookup(const YAML::Node& map, const std::string& key) {
  const YAML::Node& const_map = map;  // const access: never inserts the key
  return const_map[key];
}

//! Stores a finite number within `range` in `out`, or returns why the value is not one.
std::optional<std::string> number_problem(const YAML::Node& value, Range range, double& out) {
  const std::string expected =
      range.lo <= -kUnbounded && range.hi >= kUnbounded ? "expected a number" : "expected a number " + range.describe();
  const std::optional<double> number = to_number(value);
  if (!number) return expected + got(value);
  if (!std::isfinite(*number)) return "expected a finite number";
  if (!range.contains(*number)) return expected;
  out = *number;
  return std::nullopt;
}

}  // namespace

bool Range::contains(double value) const {
  return (lo_open ? value > lo : value >= lo) && (hi_open ? value < hi : value <= hi);
}

std::string Range::describe() const {
  const bool bounded_below = lo > -kUnbounded, bounded_above = hi < kUnbounded;
  if (!bounded_below && !bounded_above) return "any number";
  if (!bounded_above) return (lo_open ? "> " : ">= ") + exact_number_text(lo);
  if (!bounded_below) return (hi_open ? "< " : "<= ") + exact_number_text(hi);
  return std::string("in ") + (lo_open ? "(" : "[") + exact_number_text(lo) + ", " + exact_number_text(hi) +
         (hi_open ? ")" : "]");
}

//! State shared by a root Config and every child taken from it.
struct Config::Shared {
  std::string file;
  YAML::Node root;
  std::vector<std::pair<std::string, std::string>> overrides;  //!< (canonical key path, "a.b=v")
  std::set<std::string> consumed;                              //!< full paths whose value was read
  std::map<std::string, std::set<std::string>> asked;          //!< map path -> key names requested
  std::vector<std::pair<std::string, std::string>> resolved;
  std::map<std::string, std::size_t> resolved_index;
  std::vector<std::pair<std::string, std::filesystem::path>> input_files;

  //! "file:line:col" of a node, or the --set that put it there.
  std::string position(const std::string& path, const YAML::Node& node) const {
    for (auto it = overrides.rbegin(); it != overrides.rend(); ++it) {
      const std::string& set = it->first;
      if (path.compare(0, set.size(), set) == 0 &&
          (path.size() == set.size() || path[set.size()] == '.' || path[set.size()] == '['))
        return "command line --set " + it->second;
    }
    const YAML::Mark mark = node.Mark();
    if (mark.is_null()) return file;
    return file + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
  }

  void record(const std::string& path, std::string text) {
    consumed.insert(path);
    const auto [it, inserted] = resolved_index.try_emplace(path, resolved.size());
    if (inserted)
      resolved.emplace_back(path, std::move(text));
    else
      resolved[it->second].second = std::move(text);
  }

  void apply_override(const std::string& assignment);
  void reject_unknown(const YAML::Node& node, const std::string& path) const;
};

void Config::Shared::apply_override(const std::string& assignment) {
  const std::size_t equals = assignment.find('=');
  const std::string origin = "command line --set " + assignment;
  if (equals == std::string::npos || equals == 0) throw InputError(origin + ": expected key.path=value");
  YAML::Node value;
  try {
    value = YAML::Load(assignment.substr(equals + 1));
  } catch (const YAML::Exception& e) {
    throw InputError(origin + ": invalid YAML value: " + e.msg);
  }
  std::stringstream segments(assignment.substr(0, equals));
  std::string segment, path;
  YAML::Node current = root;
  std::vector<std::string> keys;
  while (std::getline(segments, segment, '.')) keys.push_back(segment);
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const std::string& key = keys[i];
    if (key.empty()) throw InputError(origin + ": empty key in '" + assignment.substr(0, equals) + "'");
    YAML::Node next;
    if (current.IsSequence()) {
      std::size_t index = 0;
      const auto result = std::from_chars(key.data(), key.data() + key.size(), index);
      if (result.ec != std::errc() || result.ptr != key.data() + key.size() || index >= current.size())
        throw InputError(origin + ": key '" + path + "' is a list of " + std::to_string(current.size()) +
                         " entries; '" + key + "' is no index into it");
      path += "[" + key + "]";
      next.reset(current[index]);
    } else if (current.IsMap() || current.IsNull() || !current.IsDefined()) {
      path = join(path, key);
      next.reset(current[key]);
    } else {
      throw InputError(origin + ": key '" + path + "' = " + yaml_text(current) + " is not a map");
    }
    if (i + 1 == keys.size())
      next = value;
    else if (!next.IsDefined() || next.IsNull())
      next = YAML::Node(YAML::NodeType::Map);
    current.reset(next);
  }
  overrides.emplace_back(path, assignment);
}

void Config::Shared::reject_unknown(const YAML::Node& node, const std::string& path) const {
  if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) reject_unknown(node[i], path + "[" + std::to_string(i) + "]");
    return;
  }
  if (!node.IsMap()) return;
  const auto asked_here = asked.find(path);
  for (const auto& entry : node) {
    const std::string key = entry.first.Scalar(), full = join(path, key);
    if (consumed.count(full)) {
      reject_unknown(entry.second, full);
      continue;
    }
    std::string message = position(full, entry.first) + ": unknown key '" + full + "'";
    std::string best;
    std::size_t best_distance = std::max<std::size_t>(2, key.size() / 3) + 1;
    if (asked_here != asked.end())
      for (const std::string& candidate : asked_here->second) {
        const std::size_t distance = edit_distance(key, candidate);
        if (candidate != key && distance < best_distance && distance < key.size())
          best = candidate, best_distance = distance;
      }
    if (!best.empty()) message += " (did you mean '" + best + "'?)";
    throw InputError(message);
  }
}

Config Config::load(const std::string& file, const std::vector<std::string>& overrides) {
  std::ifstream in(file);
  if (!in) throw InputError(file + ": cannot open scene file");
  std::stringstream text;
  text << in.rdbuf();
  return parse(text.str(), file, overrides);
}

namespace {
//! yaml-cpp keeps every entry of a map with a repeated key and answers lookups with the first, so
//! a scene that gives a key twice would run silently with one of the two values: refused here,
//! naming the key path and both lines.
void reject_duplicate_keys(const YAML::Node& node, const std::string& path, const std::string& file) {
  const auto line = [](const YAML::Node& n) { return std::to_string(n.Mark().line + 1); };
  if (node.IsMap()) {
    std::map<std::string, YAML::Node> seen;
    for (const auto& entry : node) {
      const std::string key = entry.first.Scalar();
      const std::string child = path.empty() ? key : path + "." + key;
      if (const auto first = seen.find(key); first != seen.end())
        throw InputError(file + ":" + line(entry.first) + ":" + std::to_string(entry.first.Mark().column + 1) +
                         ": key '" + child + "' is given twice (first at line " + line(first->second) +
                         "); give each key once");
      seen.emplace(key, entry.first);
      reject_duplicate_keys(entry.second, child, file);
    }
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i)
      reject_duplicate_keys(node[i], path + "[" + std::to_string(i) + "]", file);
  }
}
}  // namespace

Config Config::parse(const std::string& yaml_text_in, const std::string& name,
                     const std::vector<std::string>& overrides) {
  auto shared = std::make_shared<Shared>();
  shared->file = name;
  try {
    shared->root = YAML::Load(yaml_text_in);
  } catch (const YAML::Exception& e) {
    throw InputError(name + ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1) +
                     ": invalid YAML: " + e.msg);
  }
  if (!shared->root.IsMap() && !shared->root.IsNull())
    throw InputError(shared->position("", shared->root) + ": expected a map of keys at the top level" +
                     got(shared->root));
  if (shared->root.IsNull()) shared->root = YAML::Node(YAML::NodeType::Map);
  reject_duplicate_keys(shared->root, "", name);
  for (const std::string& assignment : overrides) shared->apply_override(assignment);
  return Config(shared, std::make_unique<YAML::Node>(shared->root), "");
}

Config::Config(std::shared_ptr<Shared> shared, std::unique_ptr<YAML::Node> node, std::string path)
    : shared_(std::move(shared)), node_(std::move(node)), path_(std::move(path)) {}
Config::Config(const Config& other)
    : shared_(other.shared_), node_(std::make_unique<YAML::Node>(*other.node_)), path_(other.path_) {}
Config& Config::operator=(const Config& other) {
  if (this != &other) {
    shared_ = other.shared_;
    node_ = std::make_unique<YAML::Node>(*other.node_);
    path_ = other.path_;
  }
  return *this;
}
Config::~Config() = default;

const std::string& Config::path() const { return path_; }
const std::string& Config::file() const { return shared_->file; }

std::vector<std::pair<std::string, std::string>> Config::resolved() const { return shared_->resolved; }

std::vector<std::pair<std::string, std::filesystem::path>> Config::input_files() const { return shared_->input_files; }

std::filesystem::path Config::input_file(const std::string& key) const {
  std::filesystem::path path(text(key));
  if (path.is_relative()) path = std::filesystem::path(file()).parent_path() / path;
  const std::string full = join(path_, key);
  auto& files = shared_->input_files;
  if (std::none_of(files.begin(), files.end(), [&](const auto& f) { return f.first == full; }))
    files.emplace_back(full, path);
  return path;
}

bool Config::has(const std::string& key) const {
  shared_->asked[path_].insert(key);
  const YAML::Node value = lookup(*node_, key);
  if (!value.IsDefined()) return false;
  if (value.IsMap() || value.IsSequence()) shared_->consumed.insert(join(path_, key));
  return true;
}

void Config::fail(const std::string& key, const std::string& reason) const {
  const std::string full = join(path_, key);
  const YAML::Node value = lookup(*node_, key);
  if (!value.IsDefined()) throw InputError(shared_->position(full, *node_) + ": key '" + full + "': " + reason);
  throw InputError(shared_->position(full, value) + ": key '" + full + "' = " + yaml_text(value) + ": " + reason);
}

double Config::number(const std::string& key, Range range) const {
  if (!has(key)) fail(key, "missing required key");
  return number(key, 0.0, range);
}

double Config::number(const std::string& key, double fallback, Range range) const {
  double value = fallback;
  if (has(key))
    if (const auto problem = number_problem(lookup(*node_, key), range, value)) fail(key, *problem);
  shared_->record(join(path_, key), exact_number_text(value));
  return value;
}

int Config::integer(const std::string& key, int fallback, int lo, int hi) const {
  const std::string expected = "expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  int value = fallback;
  if (has(key)) {
    double number = 0.0;
    if (number_problem(lookup(*node_, key), Range::closed(lo, hi), number) || number != std::floor(number))
      fail(key, expected);
    value = static_cast<int>(number);
  }
  shared_->record(join(path_, key), std::to_string(value));
  return value;
}

bool Config::flag(const std::string& key, bool fallback) const {
  bool value = fallback;
  if (has(key)) {
    const YAML::Node node = lookup(*node_, key);
    if (!node.IsScalar() || !YAML::convert<bool>::decode(node, value)) fail(key, "expected true or false");
  }
  shared_->record(join(path_, key), value ? "true" : "false");
  return value;
}

std::string Config::text(const std::string& key) const {
  if (!has(key)) fail(key, "missing required key");
  return text(key, "");
}

std::string Config::text(const std::string& key, const std::string& fallback) const {
  std::string value = fallback;
  if (has(key)) {
    const YAML::Node node = lookup(*node_, key);
    if (!node.IsScalar()) fail(key, "expected a string" + got(node));
    value = node.Scalar();
  }
  YAML::Emitter out;
  out << value;
  shared_->record(join(path_, key), out.c_str());
  return value;
}

std::string Config::choice(const std::string& key, const std::string& fallback,
                           const std::vector<std::string>& allowed) const {
  const std::string value = text(key, fallback);
  if (std::find(allowed.begin(), allowed.end(), value) == allowed.end()) {
    std::string list;
    for (const std::string& option : allowed) list += (list.empty() ? "'" : ", '") + option + "'";
    fail(key, "expected one of " + list);
  }
  return value;
}

template <int dim>
Vec<dim> Config::vector(const std::string& key, Range range) const {
  if (!has(key)) fail(key, "missing required key");
  return vector<dim>(key, Vec<dim>::Zero(), range);
}

template <int dim>
Vec<dim> Config::vector(const std::string& key, const Vec<dim>& fallback, Range range) const {
  Vec<dim> value = fallback;
  const std::string full = join(path_, key);
  if (has(key)) {
    const YAML::Node node = lookup(*node_, key);
    const std::string expected = "expected a list of " + std::to_string(dim) + " numbers";
    if (!node.IsSequence() || node.size() != std::size_t(dim)) fail(key, expected);
    for (int i = 0; i < dim; ++i) {
      const YAML::Node entry = node[i];
      if (const auto problem = number_problem(entry, range, value[i])) {
        const std::string entry_path = full + "[" + std::to_string(i) + "]";
        throw InputError(shared_->position(entry_path, entry) + ": key '" + entry_path + "' = " + yaml_text(entry) +
                         ": " + *problem);
      }
    }
  }
  std::string text = "[";
  for (int i = 0; i < dim; ++i) text += (i ? ", " : "") + exact_number_text(value[i]);
  shared_->record(full, text + "]");
  return value;
}

template Vec<2> Config::vector<2>(const std::string&, Range) const;
template Vec<3> Config::vector<3>(const std::string&, Range) const;
template Vec<2> Config::vector<2>(const std::string&, const Vec<2>&, Range) const;
template Vec<3> Config::vector<3>(const std::string&, const Vec<3>&, Range) const;

std::vector<double> Config::numbers(const std::string& key, Range range) const {
  if (!has(key)) fail(key, "missing required key");
  const YAML::Node node = lookup(*node_, key);
  if (!node.IsSequence() || node.size() == 0) fail(key, "expected a non-empty list of numbers");
  const std::string full = join(path_, key);
  std::vector<double> values(node.size());
  std::string text = "[";
  for (std::size_t i = 0; i < node.size(); ++i) {
    if (const auto problem = number_problem(node[i], range, values[i])) {
      const std::string entry_path = full + "[" + std::to_string(i) + "]";
      throw InputError(shared_->position(entry_path, node[i]) + ": key '" + entry_path + "' = " + yaml_text(node[i]) +
                       ": " + *problem);
    }
    text += (i ? ", " : "") + exact_number_text(values[i]);
  }
  shared_->record(full, text + "]");
  return values;
}

std::vector<std::string> Config::texts(const std::string& key) const {
  std::vector<std::string> values;
  if (!has(key)) return values;
  const YAML::Node node = lookup(*node_, key);
  if (!node.IsSequence()) fail(key, "expected a list of texts" + got(node));
  std::string text = "[";
  for (std::size_t i = 0; i < node.size(); ++i) {
    if (!node[i].IsScalar()) fail(key, "expected a list of texts; entry " + std::to_string(i) + got(node[i]));
    values.push_back(node[i].Scalar());
    text += (i ? ", " : "") + values.back();
  }
  shared_->record(join(path_, key), text + "]");
  return values;
}

Config Config::child(const std::string& key) const {
  if (!has(key)) fail(key, "missing required key");
  return *optional_child(key);
}

std::optional<Config> Config::optional_child(const std::string& key) const {
  if (!has(key)) return std::nullopt;
  const YAML::Node node = lookup(*node_, key);
  if (!node.IsMap()) fail(key, "expected a map of keys" + got(node));
  return Config(shared_, std::make_unique<YAML::Node>(node), join(path_, key));
}

std::vector<Config> Config::list(const std::string& key) const {
  std::vector<Config> entries;
  if (!has(key)) return entries;
  const YAML::Node node = lookup(*node_, key);
  const std::string full = join(path_, key);
  if (!node.IsSequence()) fail(key, "expected a list of maps" + got(node));
  for (std::size_t i = 0; i < node.size(); ++i) {
    const std::string entry_path = full + "[" + std::to_string(i) + "]";
    if (!node[i].IsMap())
      throw InputError(shared_->position(entry_path, node[i]) + ": key '" + entry_path + "' = " + yaml_text(node[i]) +
                       ": expected a map of keys" + got(node[i]));
    entries.push_back(Config(shared_, std::make_unique<YAML::Node>(node[i]), entry_path));
  }
  return entries;
}

void Config::reject_unknown_keys() const { shared_->reject_unknown(shared_->root, ""); }

}  // namespace mpm
