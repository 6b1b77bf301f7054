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
#include "ctsurg/core/library_messages.h"
#include "ctsurg/preprocess/image_file_reader.h"

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

// ITK's writers lose write errors (a full disk gave a truncated .nii.gz that looked finished), so
// the file is read back through the verifying reader and compared with what was meant.
template <class T>
void verify_written(const fs::path& written, const Volume<T>& volume, const fs::path& path) {
  Volume<float> back;
  try {
    back = read_image_file(written);
  } catch (const InputError& e) {
    throw RuntimeError(path.string() + ": the written file does not read back (" + e.field() + ": " + e.problem() + ")");
  }
  if (!back.geometry.same_lattice(volume.geometry, 1e-3) || back.voxels.size() != volume.voxels.size()) {
    throw RuntimeError(path.string() + ": the written file does not read back with the volume's geometry");
  }
  for (std::size_t n = 0; n < back.voxels.size(); ++n) {
    if (back.voxels[n] != static_cast<float>(volume.voxels[n])) {
      throw RuntimeError(path.string() + ": the written file reads back a different value at voxel " + std::to_string(n));
    }
  }
}

template <class T>
void write_typed(const Volume<T>& volume, const fs::path& path, OutputUnit* unit) {
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

  OutputUnit own;
  // Its temporary name keeps the suffix that ITK picks the format from.
  AtomicOutput& out = (unit ? *unit : own).add(path);
  auto writer = itk::ImageFileWriter<Image>::New();
  writer->SetImageIO(format.io);
  writer->SetFileName(out.temp_path().string());
  writer->SetInput(image);
  {
    LibraryMessages said;
    try {
      writer->Update();
    } catch (const itk::ExceptionObject& e) {
      throw RuntimeError(path.string() + ": cannot write image: " + with_library_text(itk_reason(e), said.take()));
    }
    if (const std::string text = said.take(); !text.empty()) {
      throw RuntimeError(path.string() + ": " + with_library_text("the image library reported a problem while writing", text));
    }
  }
  verify_written(out.temp_path(), volume, path);
  if (!unit) own.commit();
}

}  // namespace

void check_image_output_path(const fs::path& path) {
  writable_format(path);
  check_output_path(path);
}

void write_image_file(const Volume<float>& volume, const fs::path& path, OutputUnit* unit) {
  write_typed(volume, path, unit);
}
void write_image_file(const Volume<int16_t>& volume, const fs::path& path, OutputUnit* unit) {
  write_typed(volume, path, unit);
}
void write_image_file(const Volume<uint8_t>& volume, const fs::path& path, OutputUnit* unit) {
  write_typed(volume, path, unit);
}
void write_image_file(const Volume<uint16_t>& volume, const fs::path& path, OutputUnit* unit) {
  write_typed(volume, path, unit);
}

}  // namespace ctsurg
