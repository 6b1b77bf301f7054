#include "ctsurg/core/hdf5_file.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/input_file.h"
#include "ctsurg/core/memory_guard.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <fstream>
#include <numeric>

namespace ctsurg::h5 {

namespace {

// HDF5 prints its own error stack to stderr by default; ctsurg reports errors itself.
struct SilenceHdf5 {
  SilenceHdf5() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }
};
const SilenceHdf5 g_silence;

Handle dataspace(std::span<const uint64_t> shape) {
  std::vector<hsize_t> dims(shape.begin(), shape.end());
  return Handle(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose);
}

void check(herr_t status, const std::string& file, const std::string& object, const char* what) {
  if (status < 0) throw RuntimeError(file + ": " + object + ": HDF5 failed to " + what);
}

// Chunks of about 64 KiB-1 MiB: whole rows, as many as fit in 64^3 values.
std::vector<hsize_t> chunk_shape(std::span<const uint64_t> shape) {
  std::vector<hsize_t> chunk(shape.begin(), shape.end());
  const std::size_t n = chunk.size();
  if (n == 3) {
    chunk[0] = std::min<hsize_t>(chunk[0], 16);
    chunk[1] = std::min<hsize_t>(chunk[1], 64);
    chunk[2] = std::min<hsize_t>(chunk[2], 256);
  } else if (n >= 1) {
    chunk[0] = std::min<hsize_t>(chunk[0], 65536);
  }
  for (auto& c : chunk) c = std::max<hsize_t>(c, 1);
  return chunk;
}

std::string type_name(hid_t type) {
  const H5T_class_t cls = H5Tget_class(type);
  const std::size_t size = H5Tget_size(type);
  if (cls == H5T_FLOAT) return size == 4 ? "float32" : "float64";
  if (cls == H5T_INTEGER) {
    const bool is_signed = H5Tget_sign(type) == H5T_SGN_2;
    return std::string(is_signed ? "int" : "uint") + std::to_string(size * 8);
  }
  if (cls == H5T_STRING) return "string";
  return "other";
}

}  // namespace

Handle& Handle::operator=(Handle&& o) noexcept {
  if (this != &o) {
    reset();
    id_ = o.id_;
    closer_ = o.closer_;
    o.id_ = -1;
  }
  return *this;
}

void Handle::reset() {
  if (id_ >= 0 && closer_) closer_(id_);
  id_ = -1;
}

herr_t Handle::close() {
  const herr_t status = id_ >= 0 && closer_ ? closer_(id_) : herr_t{0};
  id_ = -1;
  return status;
}

template <> hid_t native_type<uint8_t>() { return H5T_NATIVE_UINT8; }
template <> hid_t native_type<int8_t>() { return H5T_NATIVE_INT8; }
template <> hid_t native_type<int16_t>() { return H5T_NATIVE_INT16; }
template <> hid_t native_type<uint16_t>() { return H5T_NATIVE_UINT16; }
template <> hid_t native_type<int32_t>() { return H5T_NATIVE_INT32; }
template <> hid_t native_type<uint32_t>() { return H5T_NATIVE_UINT32; }
template <> hid_t native_type<int64_t>() { return H5T_NATIVE_INT64; }
template <> hid_t native_type<uint64_t>() { return H5T_NATIVE_UINT64; }
template <> hid_t native_type<float>() { return H5T_NATIVE_FLOAT; }
template <> hid_t native_type<double>() { return H5T_NATIVE_DOUBLE; }

std::string Group::child_path(const std::string& name) const { return path_ == "/" ? "/" + name : path_ + "/" + name; }

bool Group::has(const std::string& name) const { return H5Lexists(id(), name.c_str(), H5P_DEFAULT) > 0; }

Group Group::create_group(const std::string& name) {
  Handle gcpl(H5Pcreate(H5P_GROUP_CREATE), H5Pclose);
  H5Pset_obj_track_times(gcpl.get(), false);
  H5Pset_link_creation_order(gcpl.get(), H5P_CRT_ORDER_TRACKED);
  Handle g(H5Gcreate2(id(), name.c_str(), H5P_DEFAULT, gcpl.get(), H5P_DEFAULT), H5Gclose);
  if (!g.valid()) throw RuntimeError(file_ + ": " + child_path(name) + ": cannot create group");
  return Group(std::move(g), file_, child_path(name));
}

Group Group::open_group(const std::string& name) const {
  if (!has(name)) throw InputError(file_, child_path(name), "group missing (not a file of the expected kind?)");
  Handle g(H5Gopen2(id(), name.c_str(), H5P_DEFAULT), H5Gclose);
  if (!g.valid()) throw InputError(file_, child_path(name), "is not a group");
  return Group(std::move(g), file_, child_path(name));
}

template <class T>
void Group::write_dataset(const std::string& name, const T* data, std::span<const uint64_t> shape) {
  const uint64_t count = std::accumulate(shape.begin(), shape.end(), uint64_t{1}, std::multiplies<>());
  Handle space = dataspace(shape);
  Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  H5Pset_obj_track_times(dcpl.get(), false);
  if (count > 0) {
    // Every non-empty dataset is chunked so that its data carries a Fletcher-32 checksum (applied
    // last, over the compressed bytes); small ones are not worth compressing.
    const auto chunk = chunk_shape(shape);
    H5Pset_chunk(dcpl.get(), static_cast<int>(chunk.size()), chunk.data());
    if (count >= 256) {
      H5Pset_shuffle(dcpl.get());
      H5Pset_deflate(dcpl.get(), 4);
    }
    H5Pset_fletcher32(dcpl.get());
  }
  Handle ds(H5Dcreate2(id(), name.c_str(), native_type<T>(), space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
            H5Dclose);
  if (!ds.valid()) throw RuntimeError(file_ + ": " + child_path(name) + ": cannot create dataset");
  if (count > 0) {
    check(H5Dwrite(ds.get(), native_type<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, data), file_, child_path(name), "write");
  }
}

std::vector<uint64_t> Group::dataset_shape(const std::string& name) const {
  if (!has(name)) throw InputError(file_, child_path(name), "dataset missing");
  Handle ds(H5Dopen2(id(), name.c_str(), H5P_DEFAULT), H5Dclose);
  if (!ds.valid()) throw InputError(file_, child_path(name), "is not a dataset");
  Handle space(H5Dget_space(ds.get()), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  std::vector<hsize_t> dims(static_cast<std::size_t>(std::max(rank, 0)));
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  return std::vector<uint64_t>(dims.begin(), dims.end());
}

std::string Group::dataset_type_name(const std::string& name) const {
  if (!has(name)) throw InputError(file_, child_path(name), "dataset missing");
  Handle ds(H5Dopen2(id(), name.c_str(), H5P_DEFAULT), H5Dclose);
  Handle type(H5Dget_type(ds.get()), H5Tclose);
  return type_name(type.get());
}

template <class T>
std::vector<T> Group::read_dataset(const std::string& name, std::vector<uint64_t>* shape_out) const {
  const auto shape = dataset_shape(name);
  uint64_t count = 1;
  for (const uint64_t d : shape) {
    if (__builtin_mul_overflow(count, d, &count)) {
      throw InputError(file_, child_path(name), "dataset shape overflows 2^64 values (corrupt file)");
    }
  }
  check_allocation(count, sizeof(T), file_, child_path(name));
  Handle ds(H5Dopen2(id(), name.c_str(), H5P_DEFAULT), H5Dclose);
  std::vector<T> out(static_cast<std::size_t>(count));
  if (count > 0 &&
      H5Dread(ds.get(), native_type<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0) {
    throw InputError(file_, child_path(name), "cannot read dataset (corrupt file or incompatible type)");
  }
  if (shape_out) *shape_out = shape;
  return out;
}

#define CTSURG_H5_INSTANTIATE(T)                                                                          \
  template void Group::write_dataset<T>(const std::string&, const T*, std::span<const uint64_t>);        \
  template std::vector<T> Group::read_dataset<T>(const std::string&, std::vector<uint64_t>*) const;
CTSURG_H5_INSTANTIATE(uint8_t)
CTSURG_H5_INSTANTIATE(int8_t)
CTSURG_H5_INSTANTIATE(int16_t)
CTSURG_H5_INSTANTIATE(uint16_t)
CTSURG_H5_INSTANTIATE(int32_t)
CTSURG_H5_INSTANTIATE(uint32_t)
CTSURG_H5_INSTANTIATE(int64_t)
CTSURG_H5_INSTANTIATE(uint64_t)
CTSURG_H5_INSTANTIATE(float)
CTSURG_H5_INSTANTIATE(double)
#undef CTSURG_H5_INSTANTIATE

namespace {

template <class T>
void write_attribute(const Group& g, const std::string& name, hid_t type, const T* values, hsize_t n, bool scalar) {
  if (H5Aexists(g.id(), name.c_str()) > 0) H5Adelete(g.id(), name.c_str());
  Handle space(scalar ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr), H5Sclose);
  Handle attr(H5Acreate2(g.id(), name.c_str(), type, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (!attr.valid()) throw RuntimeError(g.file() + ": " + g.path() + "@" + name + ": cannot create attribute");
  check(H5Awrite(attr.get(), type, values), g.file(), g.path() + "@" + name, "write attribute");
}

Handle open_attribute(const Group& g, const std::string& name) {
  if (H5Aexists(g.id(), name.c_str()) <= 0) throw InputError(g.file(), g.path() + "@" + name, "attribute missing");
  return Handle(H5Aopen(g.id(), name.c_str(), H5P_DEFAULT), H5Aclose);
}

template <class T>
std::vector<T> read_numeric_attribute(const Group& g, const std::string& name) {
  Handle attr = open_attribute(g, name);
  Handle space(H5Aget_space(attr.get()), H5Sclose);
  const hssize_t n = H5Sget_simple_extent_npoints(space.get());
  Handle type(H5Aget_type(attr.get()), H5Tclose);
  const H5T_class_t cls = H5Tget_class(type.get());
  if (cls != H5T_INTEGER && cls != H5T_FLOAT) {
    throw InputError(g.file(), g.path() + "@" + name, "attribute is not numeric");
  }
  std::vector<T> out(static_cast<std::size_t>(std::max<hssize_t>(n, 0)));
  if (!out.empty() && H5Aread(attr.get(), native_type<T>(), out.data()) < 0) {
    throw InputError(g.file(), g.path() + "@" + name, "cannot read attribute");
  }
  return out;
}

}  // namespace

void Group::set_attribute(const std::string& name, const std::string& value) {
  Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type.get(), std::max<std::size_t>(value.size(), 1));
  H5Tset_strpad(type.get(), H5T_STR_NULLPAD);
  H5Tset_cset(type.get(), H5T_CSET_UTF8);
  const std::string padded = value.empty() ? std::string(1, '\0') : value;
  write_attribute(*this, name, type.get(), padded.data(), 1, true);
}

void Group::set_attribute(const std::string& name, double value) {
  write_attribute(*this, name, H5T_NATIVE_DOUBLE, &value, 1, true);
}
void Group::set_attribute(const std::string& name, int64_t value) {
  write_attribute(*this, name, H5T_NATIVE_INT64, &value, 1, true);
}
void Group::set_attribute(const std::string& name, std::span<const double> values) {
  write_attribute(*this, name, H5T_NATIVE_DOUBLE, values.data(), values.size(), false);
}
void Group::set_attribute(const std::string& name, std::span<const int64_t> values) {
  write_attribute(*this, name, H5T_NATIVE_INT64, values.data(), values.size(), false);
}

bool Group::has_attribute(const std::string& name) const { return H5Aexists(id(), name.c_str()) > 0; }

std::string Group::string_attribute(const std::string& name) const {
  Handle attr = open_attribute(*this, name);
  Handle type(H5Aget_type(attr.get()), H5Tclose);
  if (H5Tget_class(type.get()) != H5T_STRING) throw InputError(file_, path_ + "@" + name, "attribute is not a string");
  if (H5Tis_variable_str(type.get()) > 0) {
    char* value = nullptr;
    Handle memtype(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(memtype.get(), H5T_VARIABLE);
    if (H5Aread(attr.get(), memtype.get(), &value) < 0) throw InputError(file_, path_ + "@" + name, "unreadable");
    std::string out = value ? value : "";
    H5free_memory(value);
    return out;
  }
  const std::size_t size = H5Tget_size(type.get());
  std::string out(size, '\0');
  if (H5Aread(attr.get(), type.get(), out.data()) < 0) throw InputError(file_, path_ + "@" + name, "unreadable");
  out.resize(std::strlen(out.c_str()));
  return out;
}

double Group::double_attribute(const std::string& name) const {
  const auto v = read_numeric_attribute<double>(*this, name);
  if (v.size() != 1) throw InputError(file_, path_ + "@" + name, "expected one value, found " + std::to_string(v.size()));
  return v[0];
}
int64_t Group::int_attribute(const std::string& name) const {
  const auto v = read_numeric_attribute<int64_t>(*this, name);
  if (v.size() != 1) throw InputError(file_, path_ + "@" + name, "expected one value, found " + std::to_string(v.size()));
  return v[0];
}
std::vector<double> Group::doubles_attribute(const std::string& name) const {
  return read_numeric_attribute<double>(*this, name);
}
std::vector<int64_t> Group::ints_attribute(const std::string& name) const {
  return read_numeric_attribute<int64_t>(*this, name);
}

namespace {

// The HDF5 file signature (HDF5 File Format Specification, section II.A): at byte 0, or at 512,
// 1024, 2048, ... after a user block. The superblock version is the byte after it.
constexpr std::array<unsigned char, 8> kSignature{0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};

// The superblock version, or -1 when the file holds no HDF5 signature.
int superblock_version(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(0, std::ios::end);
  const auto size = static_cast<uint64_t>(std::max<std::streamoff>(in.tellg(), 0));
  for (uint64_t at = 0; at + kSignature.size() < size; at = at == 0 ? 512 : 2 * at) {
    std::array<char, 9> head{};
    in.seekg(static_cast<std::streamoff>(at));
    if (!in.read(head.data(), head.size())) return -1;
    if (std::memcmp(head.data(), kSignature.data(), kSignature.size()) == 0) return static_cast<unsigned char>(head[8]);
  }
  return -1;
}

}  // namespace

File File::create(const std::filesystem::path& path, const std::string& display_name) {
  const std::string name = display_name.empty() ? path.string() : display_name;
  Handle fcpl(H5Pcreate(H5P_FILE_CREATE), H5Pclose);
  H5Pset_obj_track_times(fcpl.get(), false);
  H5Pset_link_creation_order(fcpl.get(), H5P_CRT_ORDER_TRACKED);
  Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  // HDF5 1.10's format: checksums on all metadata; readable by HDF5 1.10 and later.
  if (H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_V110, H5F_LIBVER_V110) < 0 ||
      H5Pset_fapl_core(fapl.get(), std::size_t{4} << 20, true) < 0 ||
      // close() writes the file now, even while a group or dataset handle is still open.
      H5Pset_fclose_degree(fapl.get(), H5F_CLOSE_STRONG) < 0) {
    throw RuntimeError(name + ": cannot set up the HDF5 file");
  }
  Handle f(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, fcpl.get(), fapl.get()), H5Fclose);
  if (!f.valid()) throw RuntimeError(name + ": cannot create HDF5 file");
  return File(std::move(f), name, path);
}

File File::open(const std::filesystem::path& path) {
  const std::string name = path.string();
  check_input_file(path);
  const int version = superblock_version(path);
  if (version < 0 || H5Fis_hdf5(path.c_str()) <= 0) throw InputError(name, "", "not an HDF5 file (or corrupt)");
  if (version < 2) {
    throw InputError(name, "superblock",
                     "HDF5 superblock version " + std::to_string(version) +
                         " has no checksums, so the file cannot be verified: it was not written by this version of "
                         "ctsurg; run the stage that made it again");
  }
  Handle f(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!f.valid()) throw InputError(name, "", "cannot open HDF5 file (corrupt, truncated or unreadable)");
  return File(std::move(f), name);
}

Group File::root() const {
  Handle g(H5Gopen2(h_.get(), "/", H5P_DEFAULT), H5Gclose);
  if (!g.valid()) throw InputError(name_, "/", "cannot open root group");
  return Group(std::move(g), name_, "/");
}

void File::close() {
  if (!h_.valid()) return;
  if (write_to_.empty()) {
    h_.reset();
    return;
  }
  // The core driver writes the whole file on flush and close, checking each write; its close(2)
  // is not checked, so the file is opened again: a file that does not open (cut short, bad
  // checksum) is an error here, and AtomicOutput's fsync catches what the device reports late.
  if (H5Fflush(h_.get(), H5F_SCOPE_GLOBAL) < 0) throw RuntimeError(name_ + ": HDF5 failed to write the file");
  if (h_.close() < 0) throw RuntimeError(name_ + ": HDF5 failed to write and close the file");
  Handle check(H5Fopen(write_to_.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!check.valid() || check.close() < 0) throw RuntimeError(name_ + ": the file written does not read back");
}

}  // namespace ctsurg::h5
