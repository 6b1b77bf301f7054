// ctsurg-phantom KIND OUTPUT: a synthetic CT of a shape with known analytic volume and area
// (synthetic_phantom.h), written as NIfTI/NRRD/MetaImage with a JSON sidecar of the true values.
#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/checked_write.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/tool_app.h"
#include "ctsurg/core/version.h"
#include "ctsurg/preprocess/image_file_writer.h"
#include "ctsurg/preprocess/synthetic_phantom.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

const char* const kTool = "ctsurg-phantom";

// "s" or "x,y,z" as numbers; InputError naming `option` otherwise. `allow_one` repeats a single
// value on all three axes.
Eigen::Vector3d parse_triple(const std::string& text, const char* option, bool allow_one) {
  std::vector<double> values;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    item.erase(std::remove_if(item.begin(), item.end(), [](unsigned char c) { return std::isspace(c); }), item.end());
    double v = 0.0;
    const auto [end, ec] = std::from_chars(item.data(), item.data() + item.size(), v);
    if (item.empty() || ec != std::errc() || end != item.data() + item.size()) {
      throw ctsurg::InputError(kTool, option, "'" + text + "' is not a comma-separated list of numbers");
    }
    values.push_back(v);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (values.size() == 1 && allow_one) return Eigen::Vector3d::Constant(values[0]);
  if (values.size() != 3) {
    throw ctsurg::InputError(kTool, option,
                             std::string("expected ") + (allow_one ? "one value or " : "") + "three values x,y,z, got '" +
                                 text + "'");
  }
  return {values[0], values[1], values[2]};
}

// OUTPUT with its image suffix replaced by .json: "ct/sphere.nii.gz" -> "ct/sphere.json".
fs::path sidecar_path(const fs::path& image) {
  std::string name = image.filename().string();
  std::string low = name;
  std::transform(low.begin(), low.end(), low.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* suffix : {".nii.gz", ".nii", ".nrrd", ".mha"}) {
    const std::string s = suffix;
    if (low.size() > s.size() && low.compare(low.size() - s.size(), s.size(), s) == 0) {
      name.resize(name.size() - s.size());
      break;
    }
  }
  return image.parent_path() / (name + ".json");
}

nlohmann::json vec(const Eigen::Vector3d& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); }

}  // namespace

int main(int argc, char** argv) {
  std::string kind_name, output, label_out, spacing_text = "1", semi_axes_text = "30,22,16", centre_text = "0,0,0";
  ctsurg::PhantomShape shape;
  ctsurg::PhantomRasterOptions options;
  // Options that only make sense for some kinds, so that e.g. --radius-mm on a torus is an error
  // rather than silently ignored.
  struct KindOption {
    CLI::Option* option;
    std::vector<ctsurg::PhantomKind> kinds;
  };
  std::vector<KindOption> kind_options;
  using K = ctsurg::PhantomKind;

  return ctsurg::run_tool(
      argc, argv, kTool,
      "Write a synthetic CT phantom (sphere, ellipsoid-shell, torus, bumpy-sphere) with known analytic volume and "
      "surface area, centred at LPS (0,0,0), as NIfTI/NRRD/MetaImage plus a JSON sidecar (OUTPUT with its suffix "
      "replaced by .json) holding the analytic values. Lengths in mm, values in HU.",
      [&](CLI::App& app) {
        app.add_option("kind", kind_name, "sphere, ellipsoid-shell, torus or bumpy-sphere")->required();
        app.add_option("output", output, "CT image to write (.nii.gz, .nii, .nrrd or .mha)")->required();
        kind_options.push_back({app.add_option("--radius-mm", shape.radius_mm, "Sphere / bumpy sphere radius R")
                                    ->capture_default_str(),
                                {K::Sphere, K::BumpySphere}});
        kind_options.push_back({app.add_option("--semi-axes-mm", semi_axes_text,
                                               "Ellipsoid shell: outer semi-axes a,b,c along x,y,z")
                                    ->capture_default_str(),
                                {K::EllipsoidShell}});
        kind_options.push_back({app.add_option("--thickness-mm", shape.thickness_mm,
                                               "Ellipsoid shell: wall thickness t (inner semi-axes a-t,b-t,c-t)")
                                    ->capture_default_str(),
                                {K::EllipsoidShell}});
        kind_options.push_back({app.add_option("--major-mm", shape.major_mm, "Torus: major radius R (tube centre to axis z)")
                                    ->capture_default_str(),
                                {K::Torus}});
        kind_options.push_back(
            {app.add_option("--minor-mm", shape.minor_mm, "Torus: minor (tube) radius r")->capture_default_str(), {K::Torus}});
        kind_options.push_back({app.add_option("--bump-amplitude", shape.bump_amplitude,
                                               "Bumpy sphere: eps in r = R (1 + eps cos(m theta) sin^n(theta) cos(n phi))")
                                    ->capture_default_str(),
                                {K::BumpySphere}});
        kind_options.push_back(
            {app.add_option("--bump-m", shape.bump_m, "Bumpy sphere: m")->capture_default_str(), {K::BumpySphere}});
        kind_options.push_back(
            {app.add_option("--bump-n", shape.bump_n, "Bumpy sphere: n")->capture_default_str(), {K::BumpySphere}});
        app.add_option("--centre-mm", centre_text, "LPS position of the shape's centre, x,y,z")->capture_default_str();
        app.add_option("--spacing-mm", spacing_text, "Voxel spacing: s, or sx,sy,sz")->capture_default_str();
        app.add_option("--margin-mm", options.margin_mm, "Background around the shape's bounding box")->capture_default_str();
        app.add_option("--supersample", options.supersample, "s: s^3 samples per voxel for the inside fraction")
            ->capture_default_str();
        app.add_option("--hu-inside", options.hu_inside, "HU of the object")->capture_default_str();
        app.add_option("--hu-outside", options.hu_outside, "HU of the background")->capture_default_str();
        app.add_option("--label-out", label_out, "Also write a uint8 label mask (1 where the inside fraction >= 0.5)");
      },
      [&](const ctsurg::ToolContext&) {
        shape.kind = ctsurg::phantom_kind_from_name(kind_name, kTool);
        for (const KindOption& k : kind_options) {
          if (k.option->count() > 0 && std::find(k.kinds.begin(), k.kinds.end(), shape.kind) == k.kinds.end()) {
            throw ctsurg::InputError(kTool, k.option->get_name(),
                                     std::string("does not apply to kind ") + ctsurg::phantom_kind_name(shape.kind));
          }
        }
        shape.semi_axes_mm = parse_triple(semi_axes_text, "--semi-axes-mm", false);
        shape.centre_mm = parse_triple(centre_text, "--centre-mm", false);
        options.spacing_mm = parse_triple(spacing_text, "--spacing-mm", true);
        ctsurg::validate_phantom_shape(shape, kTool);
        ctsurg::validate_phantom_raster_options(options, kTool);

        // Every output is checked before the (possibly long) rasterisation, so a bad path costs
        // nothing and leaves nothing behind.
        const fs::path image_path = output, json_path = sidecar_path(image_path);
        ctsurg::check_image_output_path(image_path);
        if (!label_out.empty()) {
          ctsurg::check_image_output_path(label_out);
          if (fs::absolute(label_out).lexically_normal() == fs::absolute(image_path).lexically_normal()) {
            throw ctsurg::InputError(kTool, "--label-out", "must differ from OUTPUT");
          }
          ctsurg::check_output_paths({image_path, label_out, json_path}, {});
        }

        const ctsurg::PhantomRaster raster = ctsurg::rasterise_phantom(shape, options, kTool);
        const double volume = ctsurg::phantom_volume_mm3(shape), area = ctsurg::phantom_area_mm2(shape);

        nlohmann::json params;
        params["centre_mm"] = vec(shape.centre_mm);
        switch (shape.kind) {
          case K::Sphere: params["radius_mm"] = shape.radius_mm; break;
          case K::EllipsoidShell: {
            const Eigen::Vector3d outer = shape.semi_axes_mm;
            const Eigen::Vector3d inner = outer - Eigen::Vector3d::Constant(shape.thickness_mm);
            params["semi_axes_mm"] = vec(outer);
            params["thickness_mm"] = shape.thickness_mm;
            params["inner_semi_axes_mm"] = vec(inner);
            params["outer_area_mm2"] = ctsurg::ellipsoid_surface_area_mm2(outer.x(), outer.y(), outer.z());
            params["inner_area_mm2"] = ctsurg::ellipsoid_surface_area_mm2(inner.x(), inner.y(), inner.z());
            break;
          }
          case K::Torus:
            params["major_mm"] = shape.major_mm;
            params["minor_mm"] = shape.minor_mm;
            params["axis"] = "z";
            break;
          case K::BumpySphere:
            params["radius_mm"] = shape.radius_mm;
            params["bump_amplitude"] = shape.bump_amplitude;
            params["bump_m"] = shape.bump_m;
            params["bump_n"] = shape.bump_n;
            params["surface"] = "r(theta,phi) = R (1 + eps cos(m theta) sin^n(theta) cos(n phi)), theta from +z, phi from +x";
            break;
        }
        const ctsurg::ImageGeometry& g = raster.hu.geometry;
        nlohmann::json j;
        j["tool"] = kTool;
        j["version"] = ctsurg::kVersion;
        j["kind"] = ctsurg::phantom_kind_name(shape.kind);
        j["parameters"] = params;
        j["units"] = "lengths in LPS millimetres, volumes mm^3, areas mm^2, values HU";
        j["image"] = image_path.filename().string();
        j["label"] = label_out.empty() ? nlohmann::json(nullptr) : nlohmann::json(fs::path(label_out).filename().string());
        j["geometry"] = {{"dims", {g.dims[0], g.dims[1], g.dims[2]}},
                         {"spacing_mm", vec(g.spacing)},
                         {"origin_mm", vec(g.origin)},
                         {"direction", "identity"}};
        j["supersample"] = options.supersample;
        j["hu_inside"] = options.hu_inside;
        j["hu_outside"] = options.hu_outside;
        j["iso_hu"] = 0.5 * (static_cast<double>(options.hu_inside) + static_cast<double>(options.hu_outside));
        j["analytic_volume_mm3"] = volume;
        j["analytic_area_mm2"] = area;
        j["rasterised_volume_mm3"] = raster.fraction_volume_mm3;
        j["rasterised_volume_relative_error"] = (raster.fraction_volume_mm3 - volume) / volume;

        // The CT, its mask and the sidecar are one result: committed together or not at all.
        ctsurg::OutputUnit outputs;
        ctsurg::write_image_file(raster.hu, image_path, &outputs);
        if (!label_out.empty()) ctsurg::write_image_file(raster.label, label_out, &outputs);
        ctsurg::AtomicOutput& sidecar = outputs.add(json_path);
        ctsurg::write_file_checked(sidecar.temp_path(), j.dump(2) + "\n", json_path.string());
        outputs.commit();
        spdlog::info("{}: {} {} x {} x {} voxels; analytic volume {:.6g} mm^3, rasterised {:.6g} mm^3 ({:+.3g}%), area {:.6g} mm^2",
                     output, ctsurg::phantom_kind_name(shape.kind), g.dims[0], g.dims[1], g.dims[2], volume,
                     raster.fraction_volume_mm3, 100.0 * (raster.fraction_volume_mm3 - volume) / volume, area);
      });
}
