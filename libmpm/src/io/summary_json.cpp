#include <mpm/io/summary_json.h>

#include <mpm/core/error.h>
#include <mpm/io/atomic_file.h>

#include <nlohmann/json.hpp>

#include <charconv>
#include <cmath>
#include <cstdint>

namespace mpm::io {
namespace {

using Json = nlohmann::ordered_json;  // keeps the order in which sections list their keys

//! A YAML scalar as the JSON value it denotes (see write_summary).
Json parameter_value(const std::string& text) {
  if (text == "true" || text == "True" || text == "TRUE") return true;
  if (text == "false" || text == "False" || text == "FALSE") return false;
  const char* first = text.data();
  const char* last = first + text.size();
  if (text.size() > 1 && text[0] == '+' && text[1] != '-') ++first;  // from_chars rejects "+5"
  std::int64_t integer = 0;
  if (const auto [end, error] = std::from_chars(first, last, integer); error == std::errc() && end == last)
    return integer;
  double number = 0.0;
  if (const auto [end, error] = std::from_chars(first, last, number);
      error == std::errc() && end == last && std::isfinite(number))
    return number;
  return text;
}

template <class Value, class Convert>
Json section(const std::vector<std::pair<std::string, Value>>& entries, const char* name,
             const std::filesystem::path& path, Convert convert) {
  Json object = Json::object();
  for (const auto& [key, value] : entries) {
    verify<InputError>(!object.contains(key),
                       "summary '" + path.string() + "': key '" + key + "' appears twice in " + name);
    object[key] = convert(value);
  }
  return object;
}

}  // namespace

void write_summary(const std::filesystem::path& path, const std::vector<std::pair<std::string, double>>& results,
                   const std::vector<std::pair<std::string, std::string>>& parameters,
                   const std::vector<std::pair<std::string, std::string>>& info) {
  Json summary = Json::object();
  summary["results"] = section(results, "results", path,
                               [](double value) { return std::isfinite(value) ? Json(value) : Json(nullptr); });
  summary["parameters"] = section(parameters, "parameters", path, parameter_value);
  summary["info"] = section(info, "info", path, [](const std::string& text) { return Json(text); });
  // Invalid UTF-8 in a string is replaced (U+FFFD) rather than failing the whole summary.
  write_file_atomically(path, summary.dump(2, ' ', false, Json::error_handler_t::replace) + "\n");
}

}  // namespace mpm::io
