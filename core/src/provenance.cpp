#include "ctsurg/core/provenance.h"

#include "ctsurg/core/file_hash.h"

#include <hdf5.h>

namespace ctsurg {

namespace {
bool is_ctsurg_hdf5(const std::filesystem::path& path) {
  return std::filesystem::is_regular_file(path) && H5Fis_hdf5(path.c_str()) > 0;
}
}  // namespace

void Provenance::add_input(const std::filesystem::path& path) {
  InputRecord r;
  r.path = path.string();
  r.sha256 = sha256_file(path);
  r.bytes = std::filesystem::file_size(path);
  inputs.push_back(r);
  if (is_ctsurg_hdf5(path)) {
    const h5::File f = h5::File::open(path);
    nlohmann::json parent = read(f.root());
    if (!parent.is_null()) upstream.push_back(parent);
  }
}

nlohmann::json Provenance::to_json() const {
  nlohmann::json j;
  j["tool"] = tool;
  j["version"] = version;
  j["command_line"] = command_line;
  j["inputs"] = nlohmann::json::array();
  for (const auto& r : inputs) j["inputs"].push_back({{"path", r.path}, {"sha256", r.sha256}, {"bytes", r.bytes}});
  j["upstream"] = upstream;
  return j;
}

void Provenance::write(h5::Group& root) const {
  h5::Group g = root.create_group("provenance");
  g.set_attribute("tool", tool);
  g.set_attribute("version", version);
  g.set_attribute("command_line", nlohmann::json(command_line).dump());
  g.set_attribute("inputs", to_json()["inputs"].dump());
  g.set_attribute("upstream", upstream.dump());
}

nlohmann::json Provenance::read(const h5::Group& root) {
  if (!root.has("provenance")) return nullptr;
  const h5::Group g = root.open_group("provenance");
  nlohmann::json j;
  j["tool"] = g.string_attribute("tool");
  j["version"] = g.string_attribute("version");
  j["command_line"] = nlohmann::json::parse(g.string_attribute("command_line"), nullptr, false);
  j["inputs"] = nlohmann::json::parse(g.string_attribute("inputs"), nullptr, false);
  j["upstream"] = nlohmann::json::parse(g.string_attribute("upstream"), nullptr, false);
  return j;
}

}  // namespace ctsurg
