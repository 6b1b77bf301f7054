// GDCM (header scan) and ITK (pixel decoding) are confined to this file.
#include <itkGDCMImageIO.h>
#include <itkImage.h>
#include <itkImageFileReader.h>

#include <gdcmDirectory.h>
#include <gdcmScanner.h>
#include <gdcmTag.h>
#include <gdcmTrace.h>

#include "ctsurg/preprocess/dicom_series_reader.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/isolated_call.h"
#include "ctsurg/core/library_messages.h"
#include "ctsurg/core/memory_guard.h"
#include "ctsurg/core/progress_bar.h"
#include "ctsurg/preprocess/dicom_file_check.h"
#include "ctsurg/preprocess/slice_stack.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <memory>
#include <fstream>
#include <map>
#include <sstream>

namespace fs = std::filesystem;

namespace ctsurg {

namespace {

const gdcm::Tag kSeriesUid(0x0020, 0x000e), kSeriesNumber(0x0020, 0x0011), kDescription(0x0008, 0x103e),
    kModality(0x0008, 0x0060), kImageType(0x0008, 0x0008), kPosition(0x0020, 0x0032), kOrientation(0x0020, 0x0037),
    kRows(0x0028, 0x0010), kColumns(0x0028, 0x0011), kPixelSpacing(0x0028, 0x0030), kFrames(0x0028, 0x0008),
    kTransferSyntax(0x0002, 0x0010), kPixelData(0x7fe0, 0x0010), kSamplesPerPixel(0x0028, 0x0002),
    kBitsAllocated(0x0028, 0x0100);

std::string trim_dicom_padding(std::string s) {
  while (!s.empty() && (s.back() == ' ' || s.back() == '\0')) s.pop_back();
  std::size_t b = 0;
  while (b < s.size() && s[b] == ' ') ++b;
  return s.substr(b);
}

std::vector<std::string> split_backslash(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, '\\')) out.push_back(trim_dicom_padding(item));
  return out;
}

std::string upper(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  return s;
}

std::vector<double> parse_numbers(const char* value, std::size_t expected, const fs::path& file, const char* field) {
  if (!value) throw InputError(file.string(), field, "missing");
  std::vector<double> out;
  for (const auto& item : split_backslash(value)) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (end == item.c_str() || !std::isfinite(v)) {
      throw InputError(file.string(), field, "not a number: '" + item + "'");
    }
    out.push_back(v);
  }
  if (out.size() != expected) {
    throw InputError(file.string(), field,
                     "expected " + std::to_string(expected) + " values, found " + std::to_string(out.size()));
  }
  return out;
}

struct SliceHeader {
  fs::path file;
  Eigen::Vector3d position, row_dir, col_dir;
  int rows = 0, columns = 0;
  int bits_allocated = 16, samples_per_pixel = 1;
  double row_spacing = 0, column_spacing = 0;
};

SliceHeader slice_header(const gdcm::Scanner& scan, const fs::path& file) {
  const char* name = file.c_str();
  SliceHeader h;
  h.file = file;
  const auto pos = parse_numbers(scan.GetValue(name, kPosition), 3, file, "ImagePositionPatient (0020,0032)");
  const auto ori = parse_numbers(scan.GetValue(name, kOrientation), 6, file, "ImageOrientationPatient (0020,0037)");
  const auto spacing = parse_numbers(scan.GetValue(name, kPixelSpacing), 2, file, "PixelSpacing (0028,0030)");
  const auto rows = parse_numbers(scan.GetValue(name, kRows), 1, file, "Rows (0028,0010)");
  const auto cols = parse_numbers(scan.GetValue(name, kColumns), 1, file, "Columns (0028,0011)");
  h.position = Eigen::Vector3d(pos[0], pos[1], pos[2]);
  h.row_dir = Eigen::Vector3d(ori[0], ori[1], ori[2]);
  h.col_dir = Eigen::Vector3d(ori[3], ori[4], ori[5]);
  if (std::abs(h.row_dir.norm() - 1.0) > 1e-3 || std::abs(h.col_dir.norm() - 1.0) > 1e-3 ||
      std::abs(h.row_dir.dot(h.col_dir)) > 1e-3) {
    throw InputError(file.string(), "ImageOrientationPatient (0020,0037)", "not two orthogonal unit vectors");
  }
  h.row_dir.normalize();
  h.col_dir.normalize();
  // PixelSpacing = (distance between rows, distance between columns), PS3.3 10.7.1.3.
  h.row_spacing = spacing[0];
  h.column_spacing = spacing[1];
  if (!(h.row_spacing > 0) || !(h.column_spacing > 0)) {
    std::ostringstream m;
    m << "spacing must be positive, got " << spacing[0] << "\\" << spacing[1];
    throw InputError(file.string(), "PixelSpacing (0028,0030)", m.str());
  }
  if (!(rows[0] >= 1 && rows[0] <= 65535 && cols[0] >= 1 && cols[0] <= 65535)) {
    throw InputError(file.string(), "Rows/Columns", "must be whole numbers 1 .. 65535 (US, PS3.5 6.2)");
  }
  h.rows = static_cast<int>(rows[0]);
  h.columns = static_cast<int>(cols[0]);
  const auto bits = parse_numbers(scan.GetValue(name, kBitsAllocated), 1, file, "BitsAllocated (0028,0100)");
  if (bits[0] != 8 && bits[0] != 16 && bits[0] != 32) {
    throw InputError(file.string(), "BitsAllocated (0028,0100)", "must be 8, 16 or 32 for a CT image");
  }
  h.bits_allocated = static_cast<int>(bits[0]);
  if (const char* samples = scan.GetValue(name, kSamplesPerPixel)) {
    if (parse_numbers(samples, 1, file, "SamplesPerPixel (0028,0002)")[0] != 1) {
      throw InputError(file.string(), "SamplesPerPixel (0028,0002)", "must be 1: a CT image is greyscale");
    }
  }
  return h;
}

// True when the file carries the DICOM Part 10 marker "DICM" at byte 128: a file with it that GDCM
// cannot parse is a corrupt DICOM file, not an unrelated file to skip.
bool has_dicom_marker(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  char magic[4] = {};
  in.seekg(128);
  in.read(magic, 4);
  return in.gcount() == 4 && std::string(magic, 4) == "DICM";
}

// GDCM reads a truncated file without complaint (it keeps the declared length and leaves the rest
// undefined), so a cut-off copy would read as an image with garbage at the end. Checks that the
// native (uncompressed) PixelData element ends inside the file. Little-endian encodings only (the
// big-endian transfer syntax is retired); encapsulated data (undefined length) is checked by its codec.
void check_pixel_data_complete(const SliceHeader& h) {
  std::ifstream in(h.file, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  static const std::string tag("\xe0\x7f\x10\x00", 4);
  const std::size_t at = bytes.rfind(tag);
  if (at == std::string::npos) throw InputError(h.file.string(), "PixelData (7FE0,0010)", "missing");
  const auto u32 = [&](std::size_t off) -> uint64_t {
    if (off + 4 > bytes.size()) return 0xffffffffu;
    return uint64_t(uint8_t(bytes[off])) | uint64_t(uint8_t(bytes[off + 1])) << 8 | uint64_t(uint8_t(bytes[off + 2])) << 16 |
           uint64_t(uint8_t(bytes[off + 3])) << 24;
  };
  const std::string vr = bytes.substr(at + 4, 2);
  const bool explicit_long = vr == "OB" || vr == "OW" || vr == "OF" || vr == "UN";
  const uint64_t length = explicit_long ? u32(at + 8) : u32(at + 4);
  const uint64_t start = explicit_long ? at + 12 : at + 8;
  if (length == 0xffffffffu) return;  // encapsulated (compressed) fragments
  if (start + length > bytes.size()) {
    throw InputError(h.file.string(), "PixelData (7FE0,0010)",
                     "truncated file: pixel data needs " + std::to_string(length) + " bytes, the file holds " +
                         std::to_string(bytes.size() > start ? bytes.size() - start : 0));
  }
  // Native pixel data hold Rows x Columns x BitsAllocated / 8 bytes (PS3.5 8.1.1); a header whose
  // BitsAllocated claims more would make the decoder read past the element.
  const uint64_t needed = uint64_t(h.rows) * uint64_t(h.columns) * uint64_t(h.samples_per_pixel) *
                          uint64_t(h.bits_allocated) / 8;
  if (length < needed) {
    throw InputError(h.file.string(), "BitsAllocated (0028,0100)",
                     "Rows x Columns x BitsAllocated / 8 = " + std::to_string(h.rows) + " x " + std::to_string(h.columns) +
                         " x " + std::to_string(h.bits_allocated) + " / 8 = " + std::to_string(needed) +
                         " bytes, but PixelData (7FE0,0010) holds " + std::to_string(length));
  }
}

// Reads one slice file as float HU (ITK applies RescaleSlope/Intercept).
std::vector<float> read_slice(const SliceHeader& h, std::vector<std::string>* warnings) {
  check_pixel_data_complete(h);
  using Image = itk::Image<float, 3>;
  auto io = itk::GDCMImageIO::New();
  auto reader = itk::ImageFileReader<Image>::New();
  reader->SetImageIO(io);
  reader->SetFileName(h.file.string());
  {
    LibraryMessages said;
    try {
      reader->Update();
    } catch (const itk::ExceptionObject& e) {
      throw InputError(h.file.string(), "PixelData (7FE0,0010)",
                       with_library_text(std::string("cannot decode: ") + e.GetDescription(), said.take()));
    }
    if (const std::string text = said.take(); !text.empty() && warnings) {
      warnings->push_back(h.file.string() + ": the DICOM decoder said: " + text);
    }
  }
  const Image* image = reader->GetOutput();
  const auto size = image->GetLargestPossibleRegion().GetSize();
  if (int(size[0]) != h.columns || int(size[1]) != h.rows || size[2] != 1) {
    throw InputError(h.file.string(), "PixelData (7FE0,0010)", "decoded size differs from Rows/Columns");
  }
  const std::size_t n = std::size_t(h.rows) * std::size_t(h.columns);
  return std::vector<float>(image->GetBufferPointer(), image->GetBufferPointer() + n);
}

}  // namespace

std::vector<DicomSeriesInfo> scan_dicom_folder(const fs::path& folder, std::vector<std::string>* skipped) {
  if (!fs::exists(folder)) throw InputError(folder.string(), "", "folder does not exist");
  if (!fs::is_directory(folder)) throw InputError(folder.string(), "", "not a folder");
  // Vendor private tags make GDCM print dictionary warnings; the reader reports what matters itself.
  gdcm::Trace::WarningOff();
  gdcm::Trace::ErrorOff();
  gdcm::Trace::DebugOff();
  itk::Object::GlobalWarningDisplayOff();
  gdcm::Directory dir;
  dir.Load(folder.string(), true);
  std::vector<std::string> names = dir.GetFilenames();
  std::sort(names.begin(), names.end());
  if (names.empty()) throw InputError(folder.string(), "", "folder is empty: no DICOM files");

  // GDCM allocates what an element's length declares before reading it: lengths are checked first.
  for (const auto& name : names) check_dicom_element_lengths(name);
  gdcm::Scanner scan;
  for (const auto& t : {kSeriesUid, kSeriesNumber, kDescription, kModality, kImageType, kPosition, kOrientation,
                        kRows, kColumns, kPixelSpacing, kFrames})
    scan.AddTag(t);
  if (!scan.Scan(names)) throw InputError(folder.string(), "", "cannot scan the folder's files");

  std::map<std::string, DicomSeriesInfo> series;
  int dicom_files = 0;
  const auto skip = [&](const std::string& file, const std::string& why) {
    if (skipped) skipped->push_back(file + ": " + why);
  };
  for (const auto& name : names) {
    if (!scan.IsKey(name.c_str())) {
      if (has_dicom_marker(name)) throw InputError(name, "header", "corrupt DICOM file: GDCM cannot parse it");
      skip(name, "not a DICOM file");
      continue;
    }
    ++dicom_files;
    const char* uid = scan.GetValue(name.c_str(), kSeriesUid);
    const char* rows = scan.GetValue(name.c_str(), kRows);
    if (!uid || !rows) {
      skip(name, "not an image (no SeriesInstanceUID or Rows; DICOMDIR or report)");
      continue;
    }
    const char* type = scan.GetValue(name.c_str(), kImageType);
    const auto types = type ? split_backslash(upper(type)) : std::vector<std::string>{};
    if (std::find(types.begin(), types.end(), "LOCALIZER") != types.end()) {
      skip(name, "localizer (ImageType " + std::string(type) + ")");
      continue;
    }
    if (!types.empty() && types[0] == "DERIVED") {
      skip(name, "derived image (ImageType " + std::string(type) + ")");
      continue;
    }
    if (!scan.GetValue(name.c_str(), kPosition) || !scan.GetValue(name.c_str(), kOrientation)) {
      skip(name, "no ImagePositionPatient/ImageOrientationPatient");
      continue;
    }
    auto& s = series[trim_dicom_padding(uid)];
    s.series_uid = trim_dicom_padding(uid);
    const auto value = [&](const gdcm::Tag& t) {
      const char* v = scan.GetValue(name.c_str(), t);
      return v ? trim_dicom_padding(v) : std::string();
    };
    s.series_number = value(kSeriesNumber);
    s.description = value(kDescription);
    s.modality = value(kModality);
    s.files.emplace_back(name);
  }
  if (series.empty()) {
    throw InputError(folder.string(), "",
                     dicom_files == 0 ? "no DICOM files among the " + std::to_string(names.size()) + " files found"
                                      : "no DICOM image series (only localizers, derived images or non-images)");
  }
  std::vector<DicomSeriesInfo> out;
  for (auto& [uid, s] : series) out.push_back(std::move(s));
  std::sort(out.begin(), out.end(), [](const DicomSeriesInfo& a, const DicomSeriesInfo& b) {
    const long na = std::atol(a.series_number.c_str()), nb = std::atol(b.series_number.c_str());
    return na != nb ? na < nb : a.series_uid < b.series_uid;
  });
  return out;
}

namespace {

// The reading itself (in the child process of read_dicom_series); progress(done, total) per slice.
DicomVolume read_series(const fs::path& folder, const DicomReadOptions& options, const ProgressReport& progress) {
  std::vector<std::string> skipped;
  const auto all = scan_dicom_folder(folder, &skipped);
  for (const auto& s : skipped) spdlog::debug("skipped {}", s);

  const DicomSeriesInfo* chosen = nullptr;
  if (!options.series.empty()) {
    for (const auto& s : all) {
      if (s.series_uid == options.series || s.series_number == options.series) {
        if (chosen) {
          throw InputError(folder.string(), "--series",
                           "'" + options.series + "' matches several series; give the SeriesInstanceUID");
        }
        chosen = &s;
      }
    }
    if (!chosen) throw InputError(folder.string(), "--series", "no series '" + options.series + "' in the folder");
  } else if (all.size() > 1) {
    std::ostringstream m;
    m << "folder holds " << all.size() << " series; choose one with --series:";
    for (const auto& s : all) {
      m << "\n  " << s.series_uid << "  (number " << s.series_number << ", '" << s.description << "', "
        << s.files.size() << " images)";
    }
    throw InputError(folder.string(), "SeriesInstanceUID (0020,000E)", m.str());
  } else {
    chosen = &all.front();
  }

  // Re-scan the chosen series for geometry (cheap: headers only).
  gdcm::Scanner scan;
  for (const auto& t : {kPosition, kOrientation, kRows, kColumns, kPixelSpacing, kFrames, kBitsAllocated, kSamplesPerPixel})
    scan.AddTag(t);
  std::vector<std::string> names;
  for (const auto& f : chosen->files) names.push_back(f.string());
  scan.Scan(names);
  std::vector<SliceHeader> headers;
  for (const auto& f : chosen->files) {
    if (const char* frames = scan.GetValue(f.c_str(), kFrames); frames && std::atoi(frames) > 1) {
      throw InputError(f.string(), "NumberOfFrames (0028,0008)",
                       "multi-frame (enhanced) images are not supported; export the series as single-frame slices");
    }
    headers.push_back(slice_header(scan, f));
  }
  const SliceHeader& ref = headers.front();
  for (const auto& h : headers) {
    if (h.rows != ref.rows || h.columns != ref.columns) {
      throw InputError(h.file.string(), "Rows/Columns",
                       "mixed image sizes in series " + chosen->series_uid + ": " + std::to_string(h.columns) + "x" +
                           std::to_string(h.rows) + " vs " + std::to_string(ref.columns) + "x" + std::to_string(ref.rows));
    }
    if ((h.row_dir - ref.row_dir).norm() > 1e-4 || (h.col_dir - ref.col_dir).norm() > 1e-4) {
      throw InputError(h.file.string(), "ImageOrientationPatient (0020,0037)",
                       "mixed orientations in series " + chosen->series_uid + " (not one volume)");
    }
    if (std::abs(h.row_spacing - ref.row_spacing) > 1e-4 || std::abs(h.column_spacing - ref.column_spacing) > 1e-4) {
      throw InputError(h.file.string(), "PixelSpacing (0028,0030)", "mixed pixel spacing in series " + chosen->series_uid);
    }
  }
  std::vector<Eigen::Vector3d> positions;
  for (const auto& h : headers) positions.push_back(h.position);
  const SliceStack stack = analyse_slice_stack(ref.row_dir, ref.col_dir, positions, folder.string());

  DicomVolume out;
  out.source = {{"format", "dicom"},
                {"series_uid", chosen->series_uid},
                {"series_number", chosen->series_number},
                {"series_description", chosen->description},
                {"modality", chosen->modality},
                {"slices", headers.size()},
                {"gantry_tilt_deg", stack.tilt_deg},
                {"slice_gap_min_mm", stack.min_gap_mm},
                {"slice_gap_max_mm", stack.max_gap_mm},
                {"slice_step_mean_mm", stack.mean_step_mm},
                {"skipped_files", skipped.size()}};
  if (chosen->modality != "CT") {
    out.warnings.push_back("modality is '" + chosen->modality + "', not CT: values may not be Hounsfield units");
  }
  if (stack.tilt_deg > 0.01) {
    std::ostringstream m;
    m << "gantry tilt of " << stack.tilt_deg
      << " degrees: the slices are sheared along the table; the volume keeps the sheared lattice (direction "
         "matrix not orthogonal) so every voxel stays where it was scanned";
    out.warnings.push_back(m.str());
  }

  const ImageGeometry geometry =
      stack.geometry(ref.columns, ref.rows, ref.column_spacing, ref.row_spacing, headers[stack.order.front()].position);
  check_allocation(static_cast<uint64_t>(geometry.voxel_count()), sizeof(float), folder.string(), "Rows x Columns x slices");
  Volume<float> slices(geometry);
  const std::size_t plane = std::size_t(ref.rows) * std::size_t(ref.columns);
  {
    for (std::size_t k = 0; k < headers.size(); ++k) {
      const SliceHeader& h = headers[static_cast<std::size_t>(stack.order[k])];
      const auto values = read_slice(h, &out.warnings);
      for (std::size_t p = 0; p < plane; ++p) {
        if (!std::isfinite(values[p])) {
          throw InputError(h.file.string(), "PixelData (7FE0,0010)",
                           "non-finite value at column " + std::to_string(p % ref.columns) + ", row " +
                               std::to_string(p / ref.columns));
        }
      }
      std::copy(values.begin(), values.end(), slices.voxels.begin() + static_cast<std::ptrdiff_t>(k * plane));
      out.files.push_back(h.file);
      progress(k + 1, headers.size());
    }
  }

  if (stack.uneven) {
    std::ostringstream m;
    const double along_normal = std::cos(stack.tilt_deg * M_PI / 180.0);
    m << "uneven slice spacing: gaps from " << stack.min_gap_mm << " to " << stack.max_gap_mm
      << " mm along the table (" << stack.min_gap_mm * along_normal << " to " << stack.max_gap_mm * along_normal
      << " mm along the slice normal; mean step "
      << stack.mean_step_mm << " mm over " << headers.size() << " slices); ";
    if (stack.missing_slices > 0) {
      m << "about " << stack.missing_slices << " slice(s) appear to be missing (gaps that are whole multiples of "
        << stack.min_gap_mm << " mm); ";
    }
    if (options.uneven == UnevenSlicePolicy::Resample) {
      slices = resample_even_slices(slices, stack);
      m << "resampled to " << slices.geometry.dims[2] << " even slices of " << slices.geometry.spacing[2]
        << " mm by linear interpolation (--uneven-slices keep to keep the acquired slices)";
      out.source["uneven_slices"] = "resampled";
    } else {
      m << "kept the acquired slices on a " << stack.mean_step_mm
        << " mm lattice: only the first and last slices are at their true positions";
      out.source["uneven_slices"] = "kept";
    }
    out.warnings.push_back(m.str());
  }
  out.hu = std::move(slices);
  return out;
}

// A DicomVolume as bytes: a JSON line (geometry, source, warnings, files), then the voxels.
std::string serialised(const DicomVolume& v) {
  const ImageGeometry& g = v.hu.geometry;
  nlohmann::json head;
  head["dims"] = g.dims;
  head["spacing"] = {g.spacing[0], g.spacing[1], g.spacing[2]};
  head["origin"] = {g.origin[0], g.origin[1], g.origin[2]};
  head["direction"] = nlohmann::json::array();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) head["direction"].push_back(g.direction(r, c));
  head["source"] = v.source;
  head["warnings"] = v.warnings;
  head["files"] = nlohmann::json::array();
  for (const auto& f : v.files) head["files"].push_back(f.string());
  return head.dump() + "\n" +
         std::string(reinterpret_cast<const char*>(v.hu.voxels.data()), v.hu.voxels.size() * sizeof(float));
}

DicomVolume deserialised(const std::string& bytes) {
  const auto newline = bytes.find('\n');
  const nlohmann::json head = nlohmann::json::parse(bytes.substr(0, newline));
  DicomVolume v;
  ImageGeometry g;
  g.dims = head.at("dims").get<std::array<int64_t, 3>>();
  for (int a = 0; a < 3; ++a) {
    g.spacing[a] = head.at("spacing")[static_cast<std::size_t>(a)];
    g.origin[a] = head.at("origin")[static_cast<std::size_t>(a)];
  }
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) g.direction(r, c) = head.at("direction")[static_cast<std::size_t>(3 * r + c)];
  v.hu.geometry = g;
  const std::size_t count = static_cast<std::size_t>(g.voxel_count());
  if (bytes.size() - newline - 1 != count * sizeof(float)) throw RuntimeError("DICOM reading: the volume came back incomplete");
  v.hu.voxels.resize(count);
  std::memcpy(v.hu.voxels.data(), bytes.data() + newline + 1, count * sizeof(float));
  v.source = head.at("source");
  v.warnings = head.at("warnings").get<std::vector<std::string>>();
  for (const auto& f : head.at("files")) v.files.emplace_back(f.get<std::string>());
  return v;
}

}  // namespace

DicomVolume read_dicom_series(const fs::path& folder, const DicomReadOptions& options) {
  // GDCM and ITK's decoders assert and allocate on damaged files in ways no check can foresee, so the
  // folder is read in a child process (isolated_call.h): a crash there refuses the folder.
  std::unique_ptr<ProgressBar> bar;
  const std::string bytes = isolated_call(
      folder.string(),
      [&](const ProgressReport& progress) { return serialised(read_series(folder, options, progress)); },
      [&](uint64_t done, uint64_t total) {
        if (!bar) bar = std::make_unique<ProgressBar>("reading DICOM slices", total);
        bar->advance(1);
        (void)done;
      });
  bar.reset();
  return deserialised(bytes);
}

}  // namespace ctsurg
