// ITK is confined to this file: callers hand over plain volumes.
#include <itkImage.h>
#include <itkImageFileWriter.h>
#include <itkImageIOBase.h>
#include <itkImportImageContainer.h>
#include <itkMetaImageIO.h>
#include <itkNiftiImageIO.h>
#include <itkNrrdImageIO.h>

#include "itk_image_io.h"

#include "ctsurg/preprocess/image_file_writer.h"

#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/error.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <string>
#include <system_error>

namespace fs = std::filesystem;

namespace ctsurg {

namespace {

using detail::ends_with;
using detail::itk_reason;

// The suffix as spelled in `path` (case kept) and the ITK reader/writer for it.
struct WritableFormat {
  std::string suffix;
  itk::ImageIOBase::Pointer io;
};

WritableFormat writable_format(const fs::path& path) {
  const std::string name = path.filename().string();
  const std::string low = detail::lower_case(name);
  for (const char* s : {".nii.gz", ".nii", ".nrrd", ".mha"}) {
    if (ends_with(low, s) && low.size() > std::char_traits<char>::length(s)) {
      const std::string suffix = name.substr(name.size() - std::char_traits<char>::length(s));
      itk::ImageIOBase::Pointer io;
      if (ends_with(low, ".nii.gz") || ends_with(low, ".nii")) io = itk::NiftiImageIO::New().GetPointer();
      else if (ends_with(low, ".nrrd")) io = itk::NrrdImageIO::New().GetPointer();
      else io = itk::MetaImageIO::New().GetPointer();
      return {suffix, io};
    }
  }
  if (ends_with(low, ".nhdr") || ends_with(low, ".mhd") || ends_with(low, ".hdr") || ends_with(low, ".img")) {
    throw InputError(path.string(), "file name",
                     "detached-header formats cannot be written atomically; use .nii, .nii.gz, .nrrd or .mha");
  }
  throw InputError(path.string(), "file name", "unknown image format; expected .nii, .nii.gz, .nrrd or .mha");
}

template <class T>
void write_typed(const Volume<T>& volume, const fs::path& path) {
  const WritableFormat format = writable_format(path);
  const ImageGeometry& g = volume.geometry;
  g.validate(path.string());
  if (static_cast<int64_t>(volume.voxels.size()) != g.voxel_count()) {
    throw RuntimeError(path.string() + ": volume holds " + std::to_string(volume.voxels.size()) +
                       " voxels but its geometry says " + std::to_string(g.voxel_count()));
  }

  using Image = itk::Image<T, 3>;
  auto image = Image::New();
  typename Image::RegionType region;
  typename Image::SpacingType spacing;
  typename Image::PointType origin;
  typename Image::DirectionType direction;
  for (unsigned a = 0; a < 3; ++a) {
    region.SetIndex(a, 0);
    region.SetSize(a, static_cast<itk::SizeValueType>(g.dims[a]));
    spacing[a] = g.spacing[a];
    origin[a] = g.origin[a];
    for (unsigned r = 0; r < 3; ++r) direction(r, a) = g.direction(r, a);
  }
  image->SetRegions(region);
  image->SetSpacing(spacing);
  image->SetOrigin(origin);
  image->SetDirection(direction);
  // The writer only reads the buffer, so it borrows the volume's memory instead of copying it
  // (a CT can be gigabytes); the container must not free it.
  auto container = Image::PixelContainer::New();
  container->SetImportPointer(const_cast<T*>(volume.voxels.data()), static_cast<itk::SizeValueType>(volume.voxels.size()),
                              false);
  image->SetPixelContainer(container);

  AtomicOutput out(path);  // its temporary name keeps the suffix that ITK picks the format from
  auto writer = itk::ImageFileWriter<Image>::New();
  writer->SetImageIO(format.io);
  writer->SetFileName(out.temp_path().string());
  writer->SetInput(image);
  try {
    writer->Update();
  } catch (const itk::ExceptionObject& e) {
    throw RuntimeError(path.string() + ": cannot write image: " + itk_reason(e));
  }
  out.commit();
}

}  // namespace

void check_image_output_path(const fs::path& path) {
  writable_format(path);
  if (fs::is_directory(path)) throw InputError(path.string(), "output", "is a folder, expected a file path");
  fs::path parent = path.parent_path();
  if (parent.empty()) parent = ".";
  if (!fs::is_directory(parent)) throw InputError(path.string(), "output", "folder '" + parent.string() + "' does not exist");
  if (::access(parent.c_str(), W_OK) != 0) {
    throw InputError(path.string(), "output", "folder '" + parent.string() + "' is not writable");
  }
}

void write_image_file(const Volume<float>& volume, const fs::path& path) { write_typed(volume, path); }
void write_image_file(const Volume<int16_t>& volume, const fs::path& path) { write_typed(volume, path); }
void write_image_file(const Volume<uint8_t>& volume, const fs::path& path) { write_typed(volume, path); }
void write_image_file(const Volume<uint16_t>& volume, const fs::path& path) { write_typed(volume, path); }

}  // namespace ctsurg
