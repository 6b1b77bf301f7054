// ctsurg-grid CT.h5 [MASK] OUTPUT.h5: tissue selection, clean-up and downsampling of a CT to the
// occupancy grid of the spring-mass model (ctsurg HDF5 + XDMF sidecar) and a PNG preview montage.
#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/checked_write.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/hu_volume_file.h"
#include "ctsurg/core/occupancy_grid_file.h"
#include "ctsurg/core/provenance.h"
#include "ctsurg/core/tool_app.h"
#include "ctsurg/core/version.h"
#include "ctsurg/core/xdmf_sidecar.h"
#include "ctsurg/preprocess/image_file_reader.h"
#include "ctsurg/preprocess/label_resampling.h"
#include "ctsurg/preprocess/mask_cleanup.h"
#include "ctsurg/preprocess/occupancy_downsampling.h"
#include "ctsurg/preprocess/preview_montage.h"
#include "ctsurg/preprocess/slicer_segmentation.h"
#include "ctsurg/preprocess/tissue_selection.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

namespace fs = std::filesystem;

namespace {

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> parts;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, sep))
    if (!item.empty()) parts.push_back(item);
  return parts;
}

uint16_t parse_label_id(const std::string& text, const std::string& option) {
  try {
    size_t used = 0;
    const long v = std::stol(text, &used);
    if (used == text.size() && v >= 1 && v <= 65535) return static_cast<uint16_t>(v);
  } catch (const std::exception&) {
  }
  throw ctsurg::InputError(option, "", "'" + text + "' is not a label id in [1, 65535]");
}

std::string format_geometry(const ctsurg::ImageGeometry& g) {
  return fmt::format("{} x {} x {} voxels, spacing {:.6g} {:.6g} {:.6g} mm, origin {:.6g} {:.6g} {:.6g} mm", g.dims[0],
                     g.dims[1], g.dims[2], g.spacing[0], g.spacing[1], g.spacing[2], g.origin[0], g.origin[1],
                     g.origin[2]);
}

// The label/mask volume: a ctsurg HDF5 volume file (its /hu volume), a 3D Slicer segmentation
// (.seg.nrrd: its layers merged, placed exactly onto the CT's voxels, segment names added to
// `names` unless --label-names gave one), or any image file ITK reads.
ctsurg::Volume<float> read_mask_volume(const fs::path& path, const ctsurg::ImageGeometry& ct,
                                       std::map<uint16_t, std::string>& names) {
  if (ctsurg::is_slicer_segmentation_file(path)) {
    std::vector<std::string> warnings;
    const ctsurg::SlicerSegmentation seg = ctsurg::read_slicer_segmentation(path, &warnings);
    for (const auto& w : warnings) spdlog::warn("{}", w);
    for (const auto& s : seg.segments) {
      spdlog::info("{}: Segment{} '{}' (id {}): layer {}, value {} -> label {}", path.string(), s.index, s.name, s.id,
                   s.layer, s.label_value, s.label);
      names.try_emplace(s.label, s.name);
    }
    const ctsurg::Volume<uint16_t> placed = ctsurg::place_on_lattice(seg.labels, ct, path.string());
    ctsurg::Volume<float> labels(placed.geometry, 0.0f);
    std::copy(placed.voxels.begin(), placed.voxels.end(), labels.voxels.begin());
    return labels;
  }
  const std::string ext = path.extension().string();
  if (ext == ".h5" || ext == ".hdf5") return ctsurg::read_hu_volume_file(path).hu;
  return ctsurg::read_image_file(path);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> files;
  double hu_min = -std::numeric_limits<double>::infinity(), hu_max = std::numeric_limits<double>::infinity();
  bool otsu = false, no_preview = false;
  std::string labels_text, names_text, preview_path;
  std::vector<double> window{400.0, 40.0};
  ctsurg::MaskCleanupOptions cleanup;
  ctsurg::OccupancyDownsamplingOptions grid_options;
  CLI::Option *hu_min_opt = nullptr, *hu_max_opt = nullptr, *voxel_opt = nullptr, *max_dim_opt = nullptr;
  return ctsurg::run_tool(
      argc, argv, "ctsurg-grid",
      "Select a tissue in an HU volume (HU window, label/mask volume or Otsu), clean it up, and downsample it to "
      "the occupancy grid of the spring-mass model: cubic cells, exact volume fractions, dominant labels, "
      "particles (ctsurg HDF5 + XDMF), plus a PNG preview montage.",
      [&](CLI::App& app) {
        app.add_option("files", files, "CT.h5 (from ctsurg-import) [MASK (label volume over the CT, or a 3D Slicer .seg.nrrd; put onto its voxels)] OUTPUT.h5")
            ->required()
            ->expected(2, 3);
        auto* sel = app.add_option_group("selection", "exactly one of: HU window, mask file, --otsu");
        hu_min_opt = sel->add_option("--hu-min", hu_min, "Tissue: HU >= this");
        hu_max_opt = sel->add_option("--hu-max", hu_max, "Tissue: HU <= this");
        sel->add_flag("--otsu", otsu, "Tissue: HU above Otsu's threshold");
        app.add_option("--labels", labels_text, "With a mask: label ids to keep, e.g. 2,3 (default: all non-zero)");
        app.add_option("--label-names", names_text, "Tissue names, e.g. 2=kidney_right,3=kidney_left");
        app.add_flag("--keep-largest", cleanup.keep_largest, "Keep only the largest connected component");
        app.add_option("--min-component-mm3", cleanup.min_component_mm3, "Drop components smaller than this (mm^3)");
        app.add_flag("--fill-holes", cleanup.fill_holes, "Fill internal holes of the mask");
        app.add_option("--closing-mm", cleanup.closing_mm, "Morphological closing with a ball of this radius (mm)");
        voxel_opt = app.add_option("--voxel-mm", grid_options.cell_mm, "Cell edge of the occupancy grid (mm)");
        max_dim_opt = app.add_option("--max-dim", grid_options.max_dim,
                                     "Cells along the tissue's longest bounding-box axis (default 100 when "
                                     "--voxel-mm is not given)");
        app.add_option("--occupancy-threshold", grid_options.occupancy_threshold,
                       "A cell is a particle when its tissue fraction is at least this")
            ->capture_default_str();
        app.add_option("--preview", preview_path, "Preview PNG (default: OUTPUT with _preview.png)");
        app.add_flag("--no-preview", no_preview, "Do not write the preview");
        app.add_option("--preview-window", window, "Preview display window: width,level in HU")
            ->expected(2)
            ->delimiter(',')
            ->capture_default_str();
      },
      [&](const ctsurg::ToolContext& ctx) {
        const auto start = std::chrono::steady_clock::now();
        const fs::path ct_path = files.front(), output = files.back();
        const fs::path mask_path = files.size() == 3 ? fs::path(files[1]) : fs::path();
        const bool by_window = *hu_min_opt || *hu_max_opt, by_mask = !mask_path.empty();
        const int methods = int(by_window) + int(by_mask) + int(otsu);
        if (methods != 1) {
          throw ctsurg::InputError(
              "selection", "",
              methods == 0 ? "choose the tissue: --hu-min/--hu-max, a mask file (CT.h5 MASK OUTPUT.h5), or --otsu"
                           : "choose only one of --hu-min/--hu-max, a mask file and --otsu");
        }
        if (!labels_text.empty() && !by_mask) throw ctsurg::InputError("--labels", "", "needs a mask file");
        if (*voxel_opt && *max_dim_opt) throw ctsurg::InputError("--voxel-mm", "", "give either --voxel-mm or --max-dim, not both");
        if (!*voxel_opt && !*max_dim_opt) grid_options.max_dim = 100;
        if (*voxel_opt && grid_options.cell_mm == 0.0) {
          throw ctsurg::InputError("--voxel-mm", "", "cell size must be a positive number of mm, got 0");
        }
        if (!(window[0] > 0.0)) throw ctsurg::InputError("--preview-window", "", "width must be positive");
        for (const auto& [name, v] : {std::pair{"--min-component-mm3", cleanup.min_component_mm3},
                                      std::pair{"--closing-mm", cleanup.closing_mm}}) {
          if (!(v >= 0.0) || !std::isfinite(v)) throw ctsurg::InputError(name, "", "must be a non-negative number");
        }
        std::vector<uint16_t> ids;
        for (const auto& t : split(labels_text, ',')) ids.push_back(parse_label_id(t, "--labels"));
        std::map<uint16_t, std::string> names;
        for (const auto& t : split(names_text, ',')) {
          const auto eq = t.find('=');
          if (eq == std::string::npos || eq + 1 == t.size()) {
            throw ctsurg::InputError("--label-names", "", "'" + t + "' is not of the form id=name");
          }
          names[parse_label_id(t.substr(0, eq), "--label-names")] = t.substr(eq + 1);
        }
        grid_options.keep_largest_only = cleanup.keep_largest;
        grid_options.min_component_mm3 = cleanup.min_component_mm3;
        if (preview_path.empty()) preview_path = (output.parent_path() / (output.stem().string() + "_preview.png")).string();
        {
          std::vector<fs::path> outputs{output, ctsurg::xdmf_path_for(output)};
          if (!no_preview) outputs.emplace_back(preview_path);
          std::vector<fs::path> inputs{ct_path};
          if (by_mask) inputs.push_back(mask_path);
          ctsurg::check_output_paths(outputs, inputs);
        }

        const ctsurg::HuVolume ct = ctsurg::read_hu_volume_file(ct_path);
        const auto& g = ct.hu.geometry;
        ctsurg::Volume<uint16_t> mask;
        if (by_mask) {
          const ctsurg::Volume<float> labels = read_mask_volume(mask_path, g, names);
          mask = ctsurg::select_labels(labels, ids, mask_path.string());
          if (!labels.geometry.same_lattice(g)) {
            // Same voxels in another index order (e.g. rows flipped) resample exactly; anything else
            // is nearest-neighbour and reported.
            const int64_t before = ctsurg::count_tissue_voxels(mask);
            auto resampled = ctsurg::resample_labels_nearest(mask, g);
            if (ctsurg::count_tissue_voxels(resampled.labels) == 0 && before > 0) {
              throw ctsurg::InputError(mask_path.string(), "geometry",
                                       "the selected tissue lies outside the CT: mask " + format_geometry(labels.geometry) +
                                           "; CT " + format_geometry(g));
            }
            if (!resampled.exact()) {
              spdlog::warn("{}: not on the CT's voxels (mask {}; CT {}): labels resampled to the CT by nearest "
                           "neighbour, voxel centres up to {:.3g} mm apart",
                           mask_path.string(), format_geometry(labels.geometry), format_geometry(g),
                           resampled.max_offset_mm);
            } else {
              spdlog::info("{}: same voxels as the CT in another index order; reordered exactly", mask_path.string());
            }
            mask = std::move(resampled.labels);
          }
          for (const auto id : ids) {
            if (std::find(mask.voxels.begin(), mask.voxels.end(), id) == mask.voxels.end()) {
              spdlog::warn("{}: label {} does not occur", mask_path.string(), id);
            }
          }
        } else if (otsu) {
          const double t = ctsurg::otsu_threshold(ct.hu, ct_path.string());
          spdlog::info("Otsu threshold: {:.1f} HU", t);
          mask = ctsurg::select_otsu(ct.hu, ct_path.string());
        } else {
          mask = ctsurg::select_hu_window(ct.hu, hu_min, hu_max, ct_path.string());
        }
        const int64_t selected = ctsurg::count_tissue_voxels(mask);
        spdlog::info("selected {} voxels ({:.1f} mL)", selected, selected * g.voxel_volume_mm3() / 1000.0);

        mask = ctsurg::cleanup_mask(mask, cleanup);
        const int64_t kept = ctsurg::count_tissue_voxels(mask);
        if (kept == 0) {
          throw ctsurg::InputError("--min-component-mm3", "",
                                   "every connected component is smaller than " +
                                       std::to_string(cleanup.min_component_mm3) + " mm^3; nothing is left");
        }
        for (const auto id : ctsurg::labels_present(mask)) {
          if (!names.count(id)) names[id] = by_mask ? "label_" + std::to_string(id) : "tissue";
        }
        for (auto it = names.begin(); it != names.end();) {  // names of labels not in the mask are dropped
          const auto present = ctsurg::labels_present(mask);
          it = std::binary_search(present.begin(), present.end(), it->first) ? std::next(it) : names.erase(it);
        }

        const ctsurg::OccupancyGrid grid = ctsurg::downsample_occupancy(mask, grid_options, names);
        const auto& cg = grid.occupancy.geometry;
        double fraction_sum = 0.0;
        for (const float f : grid.fraction.voxels) fraction_sum += f;
        spdlog::info("cells {:.4g} mm, grid {} x {} x {}, {} particles", cg.spacing[0], cg.dims[0], cg.dims[1],
                     cg.dims[2], grid.particle_count());
        spdlog::info("tissue volume: {:.2f} mL from the cell fractions, {:.2f} mL from the full-resolution mask, "
                     "{:.2f} mL in particles",
                     fraction_sum * cg.voxel_volume_mm3() / 1000.0, kept * g.voxel_volume_mm3() / 1000.0,
                     grid.particle_count() * cg.voxel_volume_mm3() / 1000.0);

        std::string png;
        if (!no_preview) {
          ctsurg::PreviewOptions preview;
          preview.window_width = window[0];
          preview.window_level = window[1];
          png = ctsurg::encode_png(ctsurg::render_preview_montage(ct.hu, grid.mask, grid.occupancy, preview));
        }
        ctsurg::Provenance provenance{ctx.name, ctsurg::kVersion, ctx.command_line, {}, nlohmann::json::array()};
        provenance.add_input(ct_path);
        if (by_mask) provenance.add_input(mask_path);
        // The grid, its sidecar and the preview are one result, committed together: a failed
        // preview leaves the previous grid in place.
        ctsurg::OutputUnit outputs;
        if (!no_preview) {
          ctsurg::AtomicOutput& preview = outputs.add(preview_path);
          ctsurg::write_file_checked(preview.temp_path(), png, preview_path);
        }
        ctsurg::write_occupancy_grid_file(output, grid, provenance, &outputs);
        outputs.commit();
        spdlog::info("wrote {}{}", output.string(), no_preview ? std::string() : " and " + preview_path);
        spdlog::info("done in {:.2f} s",
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      });
}
