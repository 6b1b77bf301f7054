#include "ctsurg/core/ctsurg_file.h"

#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/checked_write.h"
#include "ctsurg/core/error.h"

namespace ctsurg {

void write_ctsurg_file(const std::filesystem::path& path, const std::string& format, int64_t format_version,
                       const Provenance& provenance, const std::function<void(h5::Group& root)>& fill,
                       const std::vector<XdmfLattice>& lattices, OutputUnit* unit) {
  write_ctsurg_file(path, format, format_version, provenance, fill, xdmf_document(path.filename().string(), lattices),
                    unit);
}

void write_ctsurg_file(const std::filesystem::path& path, const std::string& format, int64_t format_version,
                       const Provenance& provenance, const std::function<void(h5::Group& root)>& fill,
                       const std::string& sidecar_xml, OutputUnit* unit) {
  OutputUnit own;
  OutputUnit& outputs = unit ? *unit : own;
  AtomicOutput& out = outputs.add(path);
  AtomicOutput& sidecar = outputs.add(xdmf_path_for(path));
  {
    h5::File f = h5::File::create(out.temp_path(), path.string());
    {
      h5::Group root = f.root();
      root.set_attribute("ctsurg_format", format);
      root.set_attribute("ctsurg_format_version", format_version);
      provenance.write(root);
      fill(root);
    }
    f.close();
  }
  write_file_checked(sidecar.temp_path(), sidecar_xml, sidecar.path().string());
  if (!unit) own.commit();
}

std::string ctsurg_file_format(const std::filesystem::path& path) {
  const h5::File f = h5::File::open(path);
  const auto root = f.root();
  return root.has_attribute("ctsurg_format") ? root.string_attribute("ctsurg_format") : std::string();
}

h5::File open_ctsurg_file(const std::filesystem::path& path, const std::string& format) {
  h5::File f = h5::File::open(path);
  const h5::Group root = f.root();
  if (!root.has_attribute("ctsurg_format") || root.string_attribute("ctsurg_format") != format) {
    throw InputError(path.string(), "/@ctsurg_format", "not a ctsurg " + format + " file");
  }
  return f;
}

}  // namespace ctsurg
