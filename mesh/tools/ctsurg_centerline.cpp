// ctsurg-centerline MASK -o CENTERLINE.h5: the centerline of a vessel in a mask or label image (NIfTI,
// NRRD, MetaImage, or a ctsurg HDF5 volume file): branches between end points and junctions with the
// maximal inscribed radius at every point (mesh/centerline_extraction.h), as a ctsurg centerline file
// (.h5 + .vtk sidecar) and optionally a PNG preview (mesh/centerline_preview.h).
#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/centerline_file.h"
#include "ctsurg/core/checked_write.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/hu_volume_file.h"
#include "ctsurg/core/provenance.h"
#include "ctsurg/core/tool_app.h"
#include "ctsurg/core/version.h"
#include "ctsurg/mesh/centerline_extraction.h"
#include "ctsurg/mesh/centerline_preview.h"
#include "ctsurg/preprocess/image_file_reader.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <set>

namespace fs = std::filesystem;

namespace {

ctsurg::Volume<float> read_mask_volume(const fs::path& path) {
  const std::string ext = path.extension().string();
  if (ext == ".h5" || ext == ".hdf5") return ctsurg::read_hu_volume_file(path).hu;
  return ctsurg::read_image_file(path);
}

// The voxels of `label` (0: any non-zero value).
ctsurg::Volume<uint8_t> select_label(const ctsurg::Volume<float>& labels, int label, const std::string& file) {
  ctsurg::Volume<uint8_t> mask(labels.geometry, 0);
  int64_t count = 0;
  for (std::size_t v = 0; v < labels.voxels.size(); ++v) {
    const float x = labels.voxels[v];
    const bool in = label == 0 ? x != 0.0f : x == static_cast<float>(label);
    mask.voxels[v] = in;
    count += in;
  }
  if (count == 0 && label != 0) {
    std::set<float> present;
    for (const float x : labels.voxels) {
      if (x != 0.0f) present.insert(x);
      if (present.size() > 40) break;
    }
    std::string list;
    for (const float x : present) list += (list.empty() ? "" : ", ") + fmt::format("{}", x);
    throw ctsurg::InputError(file, "--label",
                             fmt::format("label {} does not occur; values present: {}", label, list.empty() ? "none" : list));
  }
  return mask;
}

}  // namespace

int main(int argc, char** argv) {
  std::string input, output, preview;
  int label = 0;
  ctsurg::CenterlineOptions options;
  return ctsurg::run_tool(
      argc, argv, "ctsurg-centerline",
      "Centerline of a tubular mask (a vessel): distance-ordered thinning on the exact distance transform, spur "
      "pruning and smoothing; branches between end points and junctions with the maximal inscribed radius at each "
      "point (LPS mm). Output: a ctsurg centerline file (.h5) with a .vtk polyline sidecar for ParaView. Refuses an "
      "empty mask, several pieces, loops and blobs (options keep the largest piece or cut loops).",
      [&](CLI::App& app) {
        app.add_option("mask", input, "Mask or label image: .nii, .nii.gz, .nrrd, .nhdr, .mha, .mhd, or a ctsurg volume .h5")
            ->required();
        app.add_option("-o,--output", output, "Centerline file to write (.h5; the .vtk sidecar goes beside it)")->required();
        app.add_option("--label", label, "Label to use (default 0: every non-zero voxel)")->check(CLI::Range(0, 65535));
        app.add_option("--preview", preview, "Also write a PNG: the mask from the front with the centerline coloured by radius");
        app.add_option("--spur-length", options.spur_length_factor,
                       "Prune end branches shorter than this x the radius at their junction (default 2)");
        app.add_option("--junction-merge", options.junction_merge_factor,
                       "Merge junctions closer than this x their radius (default 1)");
        app.add_option("--smoothing", options.smoothing_iterations, "Taubin smoothing passes per branch (default 10)");
        app.add_option("--min-length", options.min_length_factor,
                       "Refuse a mask whose centerline is shorter than this x its largest radius (default 3)");
        app.add_option("--radius-correction", options.radius_correction_voxels,
                       "Voxels subtracted from the distance transform for the radius (default 0.25)");
        app.add_flag("--keep-largest", options.keep_largest_component, "Keep the largest piece of a mask in several pieces");
        app.add_flag("--break-loops", options.break_loops, "Cut each loop of the centerline at its thinnest point");
      },
      [&](const ctsurg::ToolContext& ctx) {
        const auto start = std::chrono::steady_clock::now();
        const fs::path out_path = output;
        const std::string ext = out_path.extension().string();
        if (ext != ".h5" && ext != ".hdf5") {
          throw ctsurg::InputError(output, "suffix", "the centerline file must end in .h5, got '" + ext + "'");
        }
        if (!preview.empty() && fs::path(preview).extension() != ".png") {
          throw ctsurg::InputError(preview, "--preview", "the preview must end in .png");
        }
        ctsurg::validate_centerline_options(options);
        std::vector<fs::path> outputs{out_path, ctsurg::centerline_vtk_path_for(out_path)};
        if (!preview.empty()) outputs.emplace_back(preview);
        ctsurg::check_output_paths(outputs, {fs::path(input)});

        const ctsurg::Volume<uint8_t> mask = select_label(read_mask_volume(input), label, input);
        const auto& g = mask.geometry;
        spdlog::info("{}: {} x {} x {} voxels, spacing {:.3g} x {:.3g} x {:.3g} mm; {}", input, g.dims[0], g.dims[1],
                     g.dims[2], g.spacing[0], g.spacing[1], g.spacing[2],
                     label ? fmt::format("label {}", label) : std::string("every non-zero voxel"));
        ctsurg::CenterlineReport report;
        ctsurg::Centerline centerline = ctsurg::extract_centerline(mask, options, input, &report);
        centerline.label = static_cast<uint16_t>(label);
        spdlog::info("mask: {} voxels in {} piece(s){}; {} cavity voxels filled; skeleton {} voxels", report.mask_voxels,
                     report.component_sizes.size(), report.component_sizes.size() > 1 ? " (largest kept)" : "",
                     report.filled_cavity_voxels, report.skeleton_voxels);
        spdlog::info("centerline: {} branches, {} nodes, {} points, {:.1f} mm long, radius up to {:.2f} mm; {} spurs "
                     "pruned, {} junction links merged, {} loops cut",
                     centerline.branch_count(), centerline.node_count(), centerline.point_count(), report.length_mm,
                     report.max_radius_mm, report.pruned_spurs, report.merged_junctions, report.broken_loops);

        ctsurg::Provenance provenance{ctx.name, ctsurg::kVersion, ctx.command_line, {}, nlohmann::json::array()};
        provenance.add_input(input);
        ctsurg::OutputUnit unit;
        ctsurg::write_centerline_file(out_path, centerline, provenance, &unit);
        if (!preview.empty()) {
          const std::vector<uint8_t> png = ctsurg::render_centerline_preview_png(mask, centerline);
          ctsurg::AtomicOutput& out = unit.add(preview);
          ctsurg::write_file_checked(out.temp_path(), std::string_view(reinterpret_cast<const char*>(png.data()), png.size()),
                                     preview);
        }
        unit.commit();
        spdlog::info("wrote {} in {:.2f} s", output,
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      });
}
