// ctsurg-import INPUT OUTPUT.h5: CT (DICOM series folder, NIfTI, NRRD, MetaImage) to an HU volume.
#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/hu_volume_file.h"
#include "ctsurg/core/provenance.h"
#include "ctsurg/core/tool_app.h"
#include "ctsurg/core/version.h"
#include "ctsurg/core/xdmf_sidecar.h"
#include "ctsurg/preprocess/ct_import.h"

#include <spdlog/spdlog.h>

#include <filesystem>
#include <vector>

namespace fs = std::filesystem;

namespace {

// Every file the import reads: the input file and its detached data files, or a DICOM folder's files.
std::vector<fs::path> input_files(const fs::path& input) {
  std::vector<fs::path> files{input};
  std::error_code ec;
  if (fs::is_directory(input, ec)) {
    for (auto it = fs::recursive_directory_iterator(input, ec); !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
      if (it->is_regular_file(ec)) files.push_back(it->path());
    }
  } else if (fs::exists(input, ec)) {
    try {
      for (const auto& f : ctsurg::detached_data_files(input)) files.push_back(f);
    } catch (const ctsurg::InputError&) {
      // An unknown suffix or a bad header is reported by the import itself, with the same message.
    }
  }
  return files;
}

}  // namespace

int main(int argc, char** argv) {
  std::string input, output, uneven = "resample";
  double slope = 0, intercept = 0;
  ctsurg::CtImportOptions options;
  CLI::Option *slope_opt = nullptr, *intercept_opt = nullptr;
  bool data_anywhere = false;
  return ctsurg::run_tool(
      argc, argv, "ctsurg-import",
      "Import a CT scan (DICOM series folder, NIfTI .nii/.nii.gz, NRRD .nrrd/.nhdr, MetaImage .mha/.mhd) as an HU "
      "volume in LPS millimetres (ctsurg HDF5 + XDMF sidecar).",
      [&](CLI::App& app) {
        app.add_option("input", input, "CT file or DICOM series folder")->required();
        app.add_option("output", output, "HU volume file to write (.h5)")->required();
        app.add_option("--series", options.dicom.series,
                       "DICOM SeriesInstanceUID or SeriesNumber, when the folder holds several series");
        app.add_option("--uneven-slices", uneven,
                       "Unevenly spaced DICOM slices: 'resample' to even slices at the smallest gap, or 'keep' the "
                       "acquired slices on the mean step (dcm2niix's layout)")
            ->check(CLI::IsMember({"resample", "keep"}));
        slope_opt = app.add_option("--rescale-slope", slope, "Non-DICOM input: HU = value x slope + intercept");
        intercept_opt = app.add_option("--rescale-intercept", intercept, "Non-DICOM input: HU = value x slope + intercept");
        app.add_flag("--allow-data-outside", data_anywhere,
                     "Read detached data files (MetaImage ElementDataFile, NRRD data file) that lie outside the "
                     "header's folder; by default a header may only name files beside it");
      },
      [&](const ctsurg::ToolContext& ctx) {
        options.dicom.uneven = uneven == "keep" ? ctsurg::UnevenSlicePolicy::Keep : ctsurg::UnevenSlicePolicy::Resample;
        if (*slope_opt) options.rescale_slope = slope;
        if (*intercept_opt) options.rescale_intercept = intercept;
        options.data_files_anywhere = data_anywhere;
        const fs::path out_path = output;
        if (out_path.extension() != ".h5" && out_path.extension() != ".hdf5") {
          throw ctsurg::InputError(output, "suffix", "the HU volume is a ctsurg HDF5 file: name it *.h5");
        }
        ctsurg::check_output_paths({out_path, ctsurg::xdmf_path_for(out_path)}, input_files(input));
        const ctsurg::CtImport ct = ctsurg::import_ct(input, options);
        for (const auto& w : ct.warnings) spdlog::warn("{}: {}", input, w);
        ctsurg::Provenance provenance{ctx.name, ctsurg::kVersion, ctx.command_line, {}, nlohmann::json::array()};
        for (const auto& f : ct.files) provenance.add_input(f);
        ctsurg::write_hu_volume_file(output, ct.volume, provenance);
        const auto& g = ct.volume.hu.geometry;
        spdlog::info("{}: {} x {} x {} voxels of {:.4g} x {:.4g} x {:.4g} mm, HU {} .. {}", output, g.dims[0], g.dims[1],
                     g.dims[2], g.spacing[0], g.spacing[1], g.spacing[2], ct.volume.source["hu_min"].dump(),
                     ct.volume.source["hu_max"].dump());
      });
}
