#include "yaml_field.h"

#include "ctsurg/core/error.h"

#include <cmath>
#include <set>
#include <sstream>
#include <utility>

namespace ctsurg::sim {

YamlField::YamlField(YAML::Node node, std::string path, const std::string* file)
    : node_(std::move(node)), path_(std::move(path)), file_(file) {}

void YamlField::fail(const std::string& problem) const { throw InputError(*file_, path_.empty() ? "(top level)" : path_, problem); }

bool YamlField::has(const std::string& key) const { return node_.IsMap() && node_[key]; }

YamlField YamlField::child(const std::string& key) const {
  if (!node_.IsMap()) fail("expected a map (key: value pairs)");
  YAML::Node c = node_[key];
  if (!c) YamlField(c, join(key), file_).fail("missing (required)");
  return YamlField(c, join(key), file_);
}

std::vector<YamlField> YamlField::items() const {
  if (!node_.IsSequence()) fail("expected a list");
  std::vector<YamlField> out;
  for (size_t i = 0; i < node_.size(); ++i) out.emplace_back(node_[i], path_ + "[" + std::to_string(i) + "]", file_);
  return out;
}

std::vector<std::string> YamlField::keys() const {
  if (!node_.IsMap()) fail("expected a map (key: value pairs)");
  std::vector<std::string> keys;
  for (const auto& kv : node_) {
    if (!kv.first.IsScalar()) fail("a key is a list or a map; keys are plain names");
    keys.push_back(kv.first.Scalar());
  }
  return keys;
}

void YamlField::only(std::initializer_list<const char*> known) const {
  only(std::vector<std::string>(known.begin(), known.end()));
}

void YamlField::only(const std::vector<std::string>& known) const {
  if (!node_.IsMap()) fail("expected a map (key: value pairs)");
  const std::set<std::string> k(known.begin(), known.end());
  for (const auto& kv : node_) {
    if (!kv.first.IsScalar()) fail("a key is a list or a map; keys are plain names");
    const std::string key = kv.first.Scalar();
    if (!k.count(key)) {
      std::string list;
      for (const auto& s : k) list += (list.empty() ? "" : ", ") + s;
      YamlField(kv.second, join(key), file_).fail("unknown key (known here: " + list + ")");
    }
  }
}

std::string YamlField::text() const {
  if (!node_.IsScalar()) fail("expected a text value");
  return node_.Scalar();
}

double YamlField::number() const {
  if (!node_.IsScalar()) fail("expected a number");
  double v = 0;
  try {
    v = node_.as<double>();
  } catch (const YAML::Exception&) {
    fail("expected a number, got '" + node_.Scalar() + "'");
  }
  if (!std::isfinite(v)) fail("must be finite");
  return v;
}

double YamlField::positive() const {
  const double v = number();
  if (!(v > 0)) fail("must be > 0, got " + num(v));
  return v;
}

double YamlField::non_negative() const {
  const double v = number();
  if (v < 0) fail("must be >= 0, got " + num(v));
  return v;
}

int64_t YamlField::integer(int64_t lo, int64_t hi) const {
  const double v = number();
  if (v != std::floor(v) || v < static_cast<double>(lo) || v > static_cast<double>(hi)) {
    fail("expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " + node_.Scalar());
  }
  return static_cast<int64_t>(v);
}

bool YamlField::boolean() const {
  if (!node_.IsScalar()) fail("expected true or false");
  try {
    return node_.as<bool>();
  } catch (const YAML::Exception&) {
    fail("expected true or false, got '" + node_.Scalar() + "'");
  }
}

std::array<double, 3> YamlField::vec3() const {
  if (!node_.IsSequence() || node_.size() != 3) fail("expected a list of 3 numbers [x, y, z]");
  std::array<double, 3> v{};
  const auto it = items();
  for (int c = 0; c < 3; ++c) v[static_cast<size_t>(c)] = it[static_cast<size_t>(c)].number();
  return v;
}

std::string YamlField::one_of(std::initializer_list<const char*> allowed) const {
  const std::string v = text();
  std::string list;
  for (const char* a : allowed) {
    if (v == a) return v;
    list += (list.empty() ? "" : ", ") + std::string(a);
  }
  fail("'" + v + "' is not one of: " + list);
}

std::string YamlField::num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

std::string YamlField::join(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

}  // namespace ctsurg::sim
