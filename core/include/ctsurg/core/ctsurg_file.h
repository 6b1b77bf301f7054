// The frame shared by every ctsurg HDF5 file: a format name and version on the root, provenance,
// the content, and an XDMF sidecar, all written atomically together (both files appear, or none).
#pragma once

#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/hdf5_file.h"
#include "ctsurg/core/provenance.h"
#include "ctsurg/core/xdmf_sidecar.h"

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace ctsurg {

// Writes `path` (content by `fill`, under the root group) and `path` with suffix .xdmf describing
// `lattices`. `format` is the value of /@ctsurg_format, e.g. "hu_volume". Both files are committed
// together (atomic_output.h); with a `unit`, they are added to it instead and the caller commits
// the unit with the run's other outputs.
void write_ctsurg_file(const std::filesystem::path& path, const std::string& format, int64_t format_version,
                       const Provenance& provenance, const std::function<void(h5::Group& root)>& fill,
                       const std::vector<XdmfLattice>& lattices, OutputUnit* unit = nullptr);
// The same with a ready-made sidecar document (`sidecar_xml`, written to `path` with suffix .xdmf),
// for content that is not a lattice, e.g. the triangle mesh of a surface file.
void write_ctsurg_file(const std::filesystem::path& path, const std::string& format, int64_t format_version,
                       const Provenance& provenance, const std::function<void(h5::Group& root)>& fill,
                       const std::string& sidecar_xml, OutputUnit* unit = nullptr);

// Opens a ctsurg file and checks that /@ctsurg_format is `format` (InputError naming the file otherwise).
h5::File open_ctsurg_file(const std::filesystem::path& path, const std::string& format);

// /@ctsurg_format of a ctsurg file ("" when the HDF5 file has none), for tools that accept several
// kinds of file. InputError naming the file when it is not HDF5.
std::string ctsurg_file_format(const std::filesystem::path& path);

}  // namespace ctsurg
