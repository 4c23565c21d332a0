#pragma once
//! Validated access to a scene file (YAML).
//!
//! A Config is one map of the scene with its key path ("solid.material") and the position of
//! every key in its file. Every getter validates type and range and, on failure, throws an
//! InputError naming file, line, key path, value and accepted range, e.g.
//!   scene.yaml:12:7: key 'material.youngs_modulus' = -5: expected a number > 0
//! Keys set from the command line (--set a.b=v) report "command line --set a.b=v" as their
//! position. Every key that a getter reads is recorded with its resolved value (defaults
//! included) for summary.json; reject_unknown_keys() fails on the first key nobody read, with a
//! "did you mean" suggestion among the keys that were read at the same level.
#include <mpm/core/types.h>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace YAML {
class Node;
}

namespace mpm {

//! An interval of accepted values; describe() renders it for error messages ("> 0", "in [0, 90)").
struct Range {
  double lo = -1e308, hi = 1e308;
  bool lo_open = false, hi_open = false;

  static Range positive() { return {0.0, 1e308, true, false}; }       //!< (0, inf)
  static Range non_negative() { return {0.0, 1e308, false, false}; }  //!< [0, inf)
  static Range closed(double a, double b) { return {a, b, false, false}; }
  static Range open(double a, double b) { return {a, b, true, true}; }
  static Range half_open(double a, double b) { return {a, b, false, true}; }  //!< [a, b)
  static Range any() { return {}; }
  bool contains(double value) const;
  std::string describe() const;
};

class Config {
public:
  //! Parses a scene file and applies overrides of the form "a.b.c=value" (value parsed as YAML).
  static Config load(const std::string& file, const std::vector<std::string>& overrides = {});
  //! Parses YAML text; `name` stands for the file in messages.
  static Config parse(const std::string& yaml_text, const std::string& name = "<string>",
                      const std::vector<std::string>& overrides = {});

  Config(const Config&);
  Config& operator=(const Config&);
  ~Config();

  bool has(const std::string& key) const;

  double number(const std::string& key, Range range) const;                   //!< required
  double number(const std::string& key, double fallback, Range range) const;  //!< optional
  int integer(const std::string& key, int fallback, int lo, int hi) const;    //!< optional, [lo, hi]
  bool flag(const std::string& key, bool fallback) const;
  std::string text(const std::string& key) const;  //!< required
  std::string text(const std::string& key, const std::string& fallback) const;
  //! One of `allowed`; an unknown value lists the allowed ones.
  std::string choice(const std::string& key, const std::string& fallback,
                     const std::vector<std::string>& allowed) const;
  //! A sequence of exactly `dim` numbers, each within `range`.
  template <int dim>
  Vec<dim> vector(const std::string& key, Range range = Range::any()) const;
  template <int dim>
  Vec<dim> vector(const std::string& key, const Vec<dim>& fallback, Range range = Range::any()) const;

  //! A required non-empty sequence of numbers, each within `range`.
  std::vector<double> numbers(const std::string& key, Range range = Range::any()) const;
  //! An optional sequence of scalars as text (absent: empty).
  std::vector<std::string> texts(const std::string& key) const;

  Config child(const std::string& key) const;  //!< required map
  std::optional<Config> optional_child(const std::string& key) const;
  std::vector<Config> list(const std::string& key) const;  //!< sequence of maps (may be absent: empty)

  //! A required file name, resolved against the scene file's folder when relative, and recorded
  //! as an input of the run (input_files()): a restart verifies that its content is unchanged.
  std::filesystem::path input_file(const std::string& key) const;

  //! Throws an InputError for `key` of this map with a custom reason (cross-field checks).
  [[noreturn]] void fail(const std::string& key, const std::string& reason) const;
  //! Throws on the first key anywhere in the file that no getter has read.
  void reject_unknown_keys() const;

  //! Full key path of this map ("" for the root), and the file name.
  const std::string& path() const;
  const std::string& file() const;
  //! Every key read so far as (full path, resolved value as YAML text), in reading order.
  std::vector<std::pair<std::string, std::string>> resolved() const;
  //! Every file read through input_file() so far as (full key path, resolved path).
  std::vector<std::pair<std::string, std::filesystem::path>> input_files() const;

private:
  struct Shared;
  Config(std::shared_ptr<Shared> shared, std::unique_ptr<YAML::Node> node, std::string path);
  std::shared_ptr<Shared> shared_;
  std::unique_ptr<YAML::Node> node_;
  std::string path_;
};

}  // namespace mpm
