// Writes a voxel volume as a single-file medical image through ITK: NIfTI (.nii, .nii.gz), NRRD
// (.nrrd) or MetaImage (.mha), chosen by the file name suffix. The counterpart of
// image_file_reader.h: read_image_file(write_image_file(v)) gives back v's values and geometry.
//
// Geometry goes to ITK as LPS mm (origin, spacing, direction exactly as in ImageGeometry); ITK's
// NIfTI writer converts it to RAS and writes both sform and qform (as float32, so a NIfTI round
// trip keeps geometry to about 1e-6 relative). Detached-header formats (.nhdr, .mhd, .hdr/.img)
// are refused: their two files cannot be replaced in one atomic rename.
//
// Every write is atomic: the image goes to a hidden temporary file in the output folder whose name
// ends in the real suffix (ITK and the NIfTI library pick the format and gzip compression from
// it), then is renamed into place through AtomicOutput. A failure leaves no file behind and never
// touches an existing file of that name. Output bytes depend only on the volume (no timestamps).
// ITK's writers do not report every write error (a full disk gave a truncated file), so the
// temporary file is read back through the verifying reader (image_file_reader.h) and compared with
// the volume, value for value, before it is committed.
#pragma once

#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/volume.h"

#include <cstdint>
#include <filesystem>

namespace ctsurg {

// Throws InputError naming `path` unless its suffix is one write_image_file can write and its
// folder exists and is writable. Tools call it for every output before starting long work.
void check_image_output_path(const std::filesystem::path& path);

// Writes `volume` (geometry.dims voxels, x fastest; HU or labels, stored in the file with the
// volume's own voxel type: float32, int16, uint8 or uint16) to `path`. InputError for an
// unsupported suffix or a missing/unwritable folder, or for invalid geometry (the message names
// `path`); RuntimeError when ITK fails to write or the file does not read back. With a `unit`, the
// file is added to it and committed with the run's other outputs (atomic_output.h).
void write_image_file(const Volume<float>& volume, const std::filesystem::path& path, OutputUnit* unit = nullptr);
void write_image_file(const Volume<int16_t>& volume, const std::filesystem::path& path, OutputUnit* unit = nullptr);
void write_image_file(const Volume<uint8_t>& volume, const std::filesystem::path& path, OutputUnit* unit = nullptr);
void write_image_file(const Volume<uint16_t>& volume, const std::filesystem::path& path, OutputUnit* unit = nullptr);

}  // namespace ctsurg
