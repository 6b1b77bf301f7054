// Private helpers shared by the ITK-based image reader and writer (not installed, not public).
#pragma once

#include <itkMacro.h>
#include <itkImageIOBase.h>
#include <itkMetaImageIO.h>
#include <itkNiftiImageIO.h>
#include <itkNrrdImageIO.h>

#include "ctsurg/preprocess/image_file_reader.h"

#include <algorithm>
#include <cctype>
#include <string>

namespace ctsurg::detail {

inline std::string lower_case(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

inline bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

inline itk::ImageIOBase::Pointer make_image_io(ImageFileFormat format) {
  switch (format) {
    case ImageFileFormat::Nifti: return itk::NiftiImageIO::New().GetPointer();
    case ImageFileFormat::Nrrd: return itk::NrrdImageIO::New().GetPointer();
    case ImageFileFormat::MetaImage: return itk::MetaImageIO::New().GetPointer();
  }
  return nullptr;
}

// ITK exception text is long and repeats the location; keep its description only.
inline std::string itk_reason(const itk::ExceptionObject& e) {
  std::string d = e.GetDescription();
  while (!d.empty() && (d.back() == '\n' || d.back() == ' ')) d.pop_back();
  return d;
}

}  // namespace ctsurg::detail
