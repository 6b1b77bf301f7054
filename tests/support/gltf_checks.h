// Checks of the glTF files the tools write: the Khronos glTF validator (node on
// tests/support/gltf/gltf_validate.mjs, installed by scripts/install-deps.sh) and a reader of the
// JSON and the float / index accessors, to test units, axes, winding and normals.
#pragma once

#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

namespace ctsurg::test {

// Success when the Khronos glTF validator finds no error in any of `files` (.glb, or .gltf with its
// resources beside it); warnings are in its output. Fails, never skips, when node or the validator
// is absent: CI runs scripts/install-deps.sh first, which installs both.
inline ::testing::AssertionResult gltf_validates(const std::vector<std::filesystem::path>& files) {
  const std::filesystem::path folder = source_dir() / "tests" / "support" / "gltf";
  if (run_shell("command -v node").exit_code != 0) {
    return ::testing::AssertionFailure() << "node is not installed: run scripts/install-deps.sh";
  }
  if (!std::filesystem::exists(folder / "node_modules" / "gltf-validator" / "package.json")) {
    return ::testing::AssertionFailure() << "the glTF validator is not installed in " << folder
                                         << ": run scripts/install-deps.sh (npm ci there)";
  }
  std::string command = "node '" + (folder / "gltf_validate.mjs").string() + "'";
  for (const auto& f : files) command += " '" + f.string() + "'";
  const CommandResult r = run_shell(command);
  if (r.exit_code != 0) return ::testing::AssertionFailure() << "glTF validator: " << r.output;
  return ::testing::AssertionSuccess() << r.output;
}

// As gltf_validates, and also no warnings in any of `files` (infos and hints allowed).
inline ::testing::AssertionResult gltf_validates_cleanly(const std::vector<std::filesystem::path>& files) {
  const ::testing::AssertionResult r = gltf_validates(files);
  if (!r) return r;
  const std::string report = r.message();
  std::size_t clean = 0;
  for (std::size_t at = report.find(" 0 errors, 0 warnings,"); at != std::string::npos; at = report.find(" 0 errors, 0 warnings,", at + 1)) ++clean;
  if (clean != files.size()) return ::testing::AssertionFailure() << "warnings from the glTF validator: " << report;
  return ::testing::AssertionSuccess();
}

// A glTF file read back: its JSON and its one binary buffer (the GLB's BIN chunk, or buffers[0]'s
// file beside a .gltf).
struct GltfFile {
  nlohmann::json json;
  std::string bin;

  // The values of float accessor `index` (tightly packed), count * components floats.
  std::vector<float> floats(std::size_t index) const {
    const auto& a = json.at("accessors").at(index);
    const auto& view = json.at("bufferViews").at(a.at("bufferView").get<std::size_t>());
    EXPECT_EQ(a.at("componentType"), 5126);
    const std::size_t width = a.at("type") == "VEC4" ? 4 : a.at("type") == "VEC3" ? 3 : a.at("type") == "VEC2" ? 2 : 1;
    const std::size_t offset = view.value("byteOffset", std::size_t{0}) + a.value("byteOffset", std::size_t{0});
    std::vector<float> out(width * a.at("count").get<std::size_t>());
    if (offset + out.size() * 4 > bin.size()) {
      ADD_FAILURE() << "accessor " << index << " runs past the buffer";
      return {};
    }
    std::memcpy(out.data(), bin.data() + offset, out.size() * 4);
    return out;
  }
  // The values of index accessor `index` (unsigned byte, short or int).
  std::vector<uint32_t> indices(std::size_t index) const {
    const auto& a = json.at("accessors").at(index);
    const auto& view = json.at("bufferViews").at(a.at("bufferView").get<std::size_t>());
    const int type = a.at("componentType").get<int>();
    const std::size_t size = type == 5125 ? 4 : type == 5123 ? 2 : 1;
    const std::size_t offset = view.value("byteOffset", std::size_t{0}) + a.value("byteOffset", std::size_t{0});
    std::vector<uint32_t> out(a.at("count").get<std::size_t>());
    if (offset + out.size() * size > bin.size()) {
      ADD_FAILURE() << "accessor " << index << " runs past the buffer";
      return {};
    }
    for (std::size_t i = 0; i < out.size(); ++i) std::memcpy(&out[i], bin.data() + offset + i * size, size);
    return out;
  }
  // The accessor index of attribute `name` of the first primitive.
  std::size_t attribute(const std::string& name) const {
    return json.at("meshes").at(0).at("primitives").at(0).at("attributes").at(name).get<std::size_t>();
  }
};

// Reads a .glb (12-byte header, a JSON chunk, a BIN chunk) or a .gltf and the .bin it names.
inline GltfFile read_gltf(const std::filesystem::path& path) {
  const std::string bytes = read_bytes(path);
  GltfFile g;
  if (bytes.compare(0, 4, "glTF") == 0) {
    uint32_t json_len = 0, bin_len = 0;
    std::memcpy(&json_len, bytes.data() + 12, 4);
    g.json = nlohmann::json::parse(bytes.substr(20, json_len));
    std::memcpy(&bin_len, bytes.data() + 20 + json_len, 4);
    g.bin = bytes.substr(28 + json_len, bin_len);
  } else {
    g.json = nlohmann::json::parse(bytes);
    g.bin = read_bytes(path.parent_path() / g.json.at("buffers").at(0).at("uri").get<std::string>());
  }
  return g;
}

}  // namespace ctsurg::test
