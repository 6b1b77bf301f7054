// A field of a YAML document (a scenario file) with its path in the document, so that every read
// checks what it reads and every failure names the file and the field: InputError(file, "tools[1].path[0].t",
// "must be >= 0, got -1"). The scenario parser (scenario.cpp) reads every field through it.
#pragma once

#include <yaml-cpp/yaml.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <vector>

namespace ctsurg::sim {

class YamlField {
 public:
  // node: the field's node; path: its path in the document ("" = the top level); file: the document's
  // name in messages (must outlive the field).
  YamlField(YAML::Node node, std::string path, const std::string* file);

  const std::string& path() const { return path_; }
  const std::string& file() const { return *file_; }  // the document's name in messages
  // Throws InputError(file, path, problem).
  [[noreturn]] void fail(const std::string& problem) const;
  bool is_map() const { return node_.IsMap(); }
  bool is_sequence() const { return node_.IsSequence(); }
  bool is_scalar() const { return node_.IsScalar(); }

  bool has(const std::string& key) const;            // a map with that key
  YamlField child(const std::string& key) const;     // a map's child; "missing (required)" when absent
  std::vector<YamlField> items() const;              // a list's items, paths "path[i]"
  std::vector<std::string> keys() const;             // a map's keys, in the document's order
  // Refuses keys that are not in `known` (a misspelt key would otherwise be silently ignored).
  void only(std::initializer_list<const char*> known) const;
  void only(const std::vector<std::string>& known) const;

  std::string text() const;
  double number() const;                             // finite
  double positive() const;                           // > 0
  double non_negative() const;                       // >= 0
  int64_t integer(int64_t lo, int64_t hi) const;     // a whole number in [lo, hi]
  bool boolean() const;
  std::array<double, 3> vec3() const;                // [x, y, z], finite
  std::string one_of(std::initializer_list<const char*> allowed) const;

  // A number as a message shows it (shortest form).
  static std::string num(double v);

 private:
  std::string join(const std::string& key) const;
  YAML::Node node_;
  std::string path_;
  const std::string* file_;
};

// A file a scenario names (a stage output, an instrument's mesh, the trajectory): as given when absolute,
// else relative to `base` (the scenario file's folder).
inline std::filesystem::path resolve_scenario_path(const std::filesystem::path& base, const std::string& p) {
  const std::filesystem::path q(p);
  return q.is_absolute() ? q : base / q;
}

}  // namespace ctsurg::sim
