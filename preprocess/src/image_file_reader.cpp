// ITK is confined to this file (and the other *_reader/*_writer sources): it returns plain volumes.
// ITK_USE_SYSTEM_EIGEN (preprocess/CMakeLists.txt) makes ITK use the same Eigen as ctsurg.
#include <itkImage.h>
#include <itkImageFileReader.h>
#include <itkImageIOBase.h>
#include <itkMetaImageIO.h>
#include <itkNiftiImageIO.h>
#include <itkNrrdImageIO.h>

#include "itk_image_io.h"

#include "ctsurg/preprocess/image_file_reader.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/input_file.h"
#include "ctsurg/core/library_messages.h"
#include "ctsurg/core/memory_guard.h"
#include "ctsurg/preprocess/detached_data_files.h"
#include "ctsurg/preprocess/metaimage_verification.h"
#include "ctsurg/preprocess/nifti_verification.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace ctsurg {

namespace {

using detail::ends_with;
using detail::itk_reason;
using detail::lower_case;
using detail::make_image_io;

void check_file(const fs::path& path) {
  if (fs::is_directory(path)) throw InputError(path.string(), "", "is a folder; a DICOM series folder is read by ctsurg-import");
  check_input_file(path);
}

// `text` with every mention of the temporary copy `readable` replaced by the user's file `path`.
std::string as_user_sees_it(std::string text, const fs::path& readable, const fs::path& path) {
  if (readable == path) return text;
  const std::string from = readable.string(), to = path.string();
  for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size())) {
    text.replace(at, from.size(), to);
  }
  return text;
}

// Verifies what ITK would take on trust (see image_file_reader.h): the file itself for NIfTI and
// MetaImage, where the detached data files lie for MetaImage and NRRD.
void verify_before_itk(const fs::path& path, ImageFileFormat format, const ImageReadOptions& options,
                       std::vector<std::string>* warnings) {
  if (format == ImageFileFormat::Nifti) {
    verify_nifti_file(path, warnings);
  } else if (format == ImageFileFormat::MetaImage) {
    verify_metaimage_file(path, options.data_files_anywhere, warnings);
  } else if (!options.data_files_anywhere) {
    for (const auto& name : detached_data_file_names(path)) check_data_file_beside_header(path, name, "data file");
  }
}

ImageGeometry geometry_from(const itk::ImageIOBase& io, const fs::path& path) {
  if (io.GetNumberOfDimensions() < 2 || io.GetNumberOfDimensions() > 4) {
    throw InputError(path.string(), "dimensions",
                     "expected a 3D image, found " + std::to_string(io.GetNumberOfDimensions()) + " dimensions");
  }
  ImageGeometry g;
  const unsigned n = std::min(3u, io.GetNumberOfDimensions());
  for (unsigned a = 0; a < n; ++a) {
    g.dims[a] = static_cast<int64_t>(io.GetDimensions(a));
    g.spacing[a] = io.GetSpacing(a);
    g.origin[a] = io.GetOrigin(a);
    const auto dir = io.GetDirection(a);
    for (unsigned r = 0; r < n; ++r) g.direction(r, a) = dir[r];
  }
  if (n == 2) {
    g.dims[2] = 1;
    g.direction.col(2) = g.direction.col(0).cross(g.direction.col(1));
  }
  if (io.GetNumberOfDimensions() == 4 && io.GetDimensions(3) > 1) {
    throw InputError(path.string(), "dimensions",
                     "4D image with " + std::to_string(io.GetDimensions(3)) + " time points; expected one 3D volume");
  }
  for (int a = 0; a < 3; ++a) {
    if (!(g.spacing[a] > 0.0) || !std::isfinite(g.spacing[a])) {
      std::ostringstream s;
      s << "voxel spacing along axis " << a << " must be a positive number of mm, got " << g.spacing[a];
      throw InputError(path.string(), "spacing", s.str());
    }
  }
  g.validate(path.string());
  return g;
}

// A NRRD header that names a "space" must give "space directions", not "spacings" (NRRD format
// spec, "spacings" field). Some exporters write both; ITK then refuses the file. Such a header is
// rewritten to a temporary copy with "space directions" built from the spacings and absolute data
// file names; the copy is removed when this object dies.
class RepairedNrrdHeader {
 public:
  RepairedNrrdHeader(const fs::path& header, std::vector<std::string>* warnings) {
    std::ifstream in(header, std::ios::binary);
    std::vector<std::string> lines;
    std::string line;
    bool has_space = false, has_spacings = false, has_directions = false;
    std::string spacings;
    while (std::getline(in, line)) {
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (line.empty()) break;  // attached data follows: nothing to repair safely
      const auto colon = line.find(':');
      const std::string key = colon == std::string::npos ? "" : line.substr(0, colon);
      if (key == "space") has_space = true;
      if (key == "space directions") has_directions = true;
      if (key == "spacings") {
        has_spacings = true;
        spacings = line.substr(colon + 1);
      }
      lines.push_back(line);
    }
    const bool detached = !in.good() || in.peek() == EOF;
    if (!(has_space && has_spacings && !has_directions && detached)) return;
    std::istringstream sp(spacings);
    std::vector<double> s;
    double v;
    while (sp >> v) s.push_back(v);
    if (s.size() != 3) return;
    std::ostringstream out;
    for (const auto& l : lines) {
      const std::string key = l.substr(0, l.find(':'));
      if (key == "spacings") {
        continue;  // replaced by space directions, which must follow the space line
      } else if (key == "space") {
        out << "space: left-posterior-superior\n";
        out << "space directions: (" << s[0] << ",0,0) (0," << s[1] << ",0) (0,0," << s[2] << ")\n";
      } else if (key == "data file" || key == "datafile") {
        std::string value = l.substr(l.find(':') + 1);
        value.erase(0, value.find_first_not_of(' '));
        if (value.rfind("LIST", 0) == 0) return;  // a list follows; leave the header alone
        out << "data file: " << (header.parent_path().empty() ? fs::current_path() : fs::absolute(header.parent_path())).string()
            << "/" << value << "\n";
      } else {
        out << l << "\n";
      }
    }
    static std::atomic<int> counter{0};
    path_ = fs::temp_directory_path() / ("ctsurg-nrrd-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) +
                                         "-" + header.filename().string());
    std::ofstream(path_) << out.str() << "\n";
    if (warnings) {
      warnings->push_back("NRRD header gives 'spacings' together with 'space' (not allowed by the NRRD format): read as "
                          "an axis-aligned LPS volume with spacings" + spacings + " mm and origin 0; patient orientation is "
                          "not recorded in this file");
    }
  }
  ~RepairedNrrdHeader() {
    if (!path_.empty()) {
      std::error_code ec;
      fs::remove(path_, ec);
    }
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

ImageFileInfo read_info_from(const fs::path& readable, const fs::path& path, ImageFileFormat format,
                             std::vector<std::string>* warnings) {
  auto io = make_image_io(format);
  LibraryMessages said;
  if (!io->CanReadFile(readable.c_str())) {
    throw InputError(path.string(), "header",
                     with_library_text("not a readable " + lower_case(io->GetNameOfClass()) + " file (corrupt header?)",
                                       as_user_sees_it(said.take(), readable, path)));
  }
  io->SetFileName(readable.string());
  try {
    io->ReadImageInformation();
  } catch (const itk::ExceptionObject& e) {
    const std::string text = as_user_sees_it(said.take(), readable, path);
    throw InputError(path.string(), "header", with_library_text(as_user_sees_it(itk_reason(e), readable, path), text));
  }
  if (const std::string text = as_user_sees_it(said.take(), readable, path); !text.empty() && warnings) {
    warnings->push_back("the image library said: " + text);
  }
  if (io->GetNumberOfComponents() != 1) {
    throw InputError(path.string(), "components",
                     "expected a scalar image, found " + std::to_string(io->GetNumberOfComponents()) + " components per voxel");
  }
  ImageFileInfo info;
  info.geometry = geometry_from(*io, path);
  info.component_type = itk::ImageIOBase::GetComponentTypeAsString(io->GetComponentType());
  info.components = static_cast<int>(io->GetNumberOfComponents());
  return info;
}

}  // namespace

ImageFileFormat image_file_format(const fs::path& path) {
  const std::string name = lower_case(path.filename().string());
  if (ends_with(name, ".nii") || ends_with(name, ".nii.gz")) return ImageFileFormat::Nifti;
  if (ends_with(name, ".nrrd") || ends_with(name, ".nhdr")) return ImageFileFormat::Nrrd;
  if (ends_with(name, ".mha") || ends_with(name, ".mhd")) return ImageFileFormat::MetaImage;
  throw InputError(path.string(), "file name",
                   "unknown image format; expected .nii, .nii.gz, .nrrd, .nhdr, .mha, .mhd or a DICOM folder");
}

ImageFileInfo read_image_file_info(const fs::path& path, std::vector<std::string>* warnings,
                                   const ImageReadOptions& options) {
  const ImageFileFormat format = image_file_format(path);
  check_file(path);
  verify_before_itk(path, format, options, warnings);
  if (format == ImageFileFormat::Nrrd) {
    const RepairedNrrdHeader repaired(path, warnings);
    if (!repaired.path().empty()) return read_info_from(repaired.path(), path, format, warnings);
  }
  return read_info_from(path, path, format, warnings);
}

Volume<float> read_image_file(const fs::path& path, std::vector<std::string>* warnings, const ImageReadOptions& options) {
  const ImageFileFormat format = image_file_format(path);
  check_file(path);
  const RepairedNrrdHeader repaired(format == ImageFileFormat::Nrrd ? path : fs::path(), nullptr);
  const fs::path readable = repaired.path().empty() ? path : repaired.path();
  const ImageFileInfo info = read_image_file_info(path, warnings, options);
  const int64_t count = info.geometry.voxel_count();
  // While reading, the file's own buffer (up to 8 bytes a voxel for float64/int64), ITK's float
  // image and our float copy are held at once.
  check_allocation(static_cast<uint64_t>(count), 8 + 2 * sizeof(float), path.string(), "dimensions");

  using Image = itk::Image<float, 3>;
  auto reader = itk::ImageFileReader<Image>::New();
  reader->SetImageIO(make_image_io(format));
  reader->SetFileName(readable.string());
  {
    LibraryMessages said;
    try {
      reader->Update();
    } catch (const itk::MemoryAllocationError&) {
      const std::string cap = memory_cap_note();
      throw RuntimeError(path.string() + ": voxel data: out of memory while reading" + (cap.empty() ? "" : " (" + cap + ")"));
    } catch (const itk::ExceptionObject& e) {
      const std::string text = as_user_sees_it(said.take(), readable, path);
      throw InputError(path.string(), "voxel data", with_library_text(as_user_sees_it(itk_reason(e), readable, path), text));
    }
    if (const std::string text = as_user_sees_it(said.take(), readable, path); !text.empty() && warnings) {
      warnings->push_back("the image library said: " + text);
    }
  }
  const Image* image = reader->GetOutput();
  Volume<float> v;
  v.geometry = info.geometry;
  const auto region = image->GetLargestPossibleRegion();
  if (static_cast<int64_t>(region.GetNumberOfPixels()) != count) {
    throw InputError(path.string(), "voxel data", "voxel count does not match the header");
  }
  v.voxels.assign(image->GetBufferPointer(), image->GetBufferPointer() + count);
  for (int64_t n = 0; n < count; ++n) {
    if (!std::isfinite(v.voxels[static_cast<std::size_t>(n)])) {
      const int64_t i = n % v.geometry.dims[0], j = (n / v.geometry.dims[0]) % v.geometry.dims[1],
                    k = n / (v.geometry.dims[0] * v.geometry.dims[1]);
      throw InputError(path.string(), "voxel data",
                       "non-finite value (NaN or infinity) at voxel (" + std::to_string(i) + ", " + std::to_string(j) +
                           ", " + std::to_string(k) + ")");
    }
  }
  return v;
}

}  // namespace ctsurg
