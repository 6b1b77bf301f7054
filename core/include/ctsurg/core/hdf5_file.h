// A small RAII layer over the HDF5 C API: the exchange format between all ctsurg stages
// (docs/formats.md). Datasets are chunked and deflate-compressed with the shuffle filter; object
// modification times are not recorded, so the same content gives byte-identical files.
// Every failure names the file and the object: "grid.h5: /grid/fraction: dataset missing".
//
// Verified both ways:
//  - Files are written in the HDF5 1.10 format (superblock version 3, version 2 object headers,
//    checksummed chunk indexes), so every piece of metadata carries a checksum, and every dataset is
//    chunked with the Fletcher-32 filter, so every chunk of data does too: a flipped bit or a cut
//    file is refused by the library instead of read as garbage or crashing it.
//  - A file is built in memory (HDF5's core driver) and written to disk in one pass on flush and
//    close, whose errors are checked; close() then opens the written file again. HDF5's default
//    driver wrote piecemeal and lost some errors (a full disk could leave an unreadable file that
//    looked finished, and the library crashed at exit after one); here a failed write is a
//    RuntimeError naming the file, and the writer's commit (atomic_output.h) fsyncs it.
//  - open() refuses a file whose superblock is older than version 2 (no checksums: not written by
//    this ctsurg), and anything that is not a regular file.
#pragma once

#include <hdf5.h>

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

namespace ctsurg::h5 {

// Owns one hid_t and closes it with the matching H5*close.
class Handle {
 public:
  using Closer = herr_t (*)(hid_t);
  Handle() = default;
  Handle(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  ~Handle() { reset(); }
  Handle(Handle&& o) noexcept : id_(o.id_), closer_(o.closer_) { o.id_ = -1; }
  Handle& operator=(Handle&& o) noexcept;
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  void reset();
  // Closes the handle now and returns the closer's status (reset() ignores it).
  herr_t close();

 private:
  hid_t id_ = -1;
  Closer closer_ = nullptr;
};

// HDF5 type for a C++ scalar type.
template <class T>
hid_t native_type();

class Group {
 public:
  Group(Handle handle, std::string file, std::string path) : h_(std::move(handle)), file_(std::move(file)), path_(std::move(path)) {}
  const std::string& file() const { return file_; }
  const std::string& path() const { return path_; }  // "/" or "/grid"
  hid_t id() const { return h_.get(); }

  bool has(const std::string& name) const;
  Group create_group(const std::string& name);
  Group open_group(const std::string& name) const;  // InputError when missing

  // Datasets. `shape` is in C order (slowest first). Data is written chunked and compressed when it
  // holds more than a few hundred values.
  template <class T>
  void write_dataset(const std::string& name, const T* data, std::span<const uint64_t> shape);
  template <class T>
  void write_dataset(const std::string& name, const std::vector<T>& data, std::span<const uint64_t> shape) {
    write_dataset<T>(name, data.data(), shape);
  }
  // Shape of a dataset (InputError when missing).
  std::vector<uint64_t> dataset_shape(const std::string& name) const;
  // HDF5 class of a dataset's stored type, as a VoxelType-style name ("int16", "float32", ...).
  std::string dataset_type_name(const std::string& name) const;
  // Reads a whole dataset, converting to T. Checks the element count against the memory guard.
  template <class T>
  std::vector<T> read_dataset(const std::string& name, std::vector<uint64_t>* shape = nullptr) const;

  // Attributes on this group.
  void set_attribute(const std::string& name, const std::string& value);
  void set_attribute(const std::string& name, double value);
  void set_attribute(const std::string& name, int64_t value);
  void set_attribute(const std::string& name, std::span<const double> values);
  void set_attribute(const std::string& name, std::span<const int64_t> values);
  bool has_attribute(const std::string& name) const;
  std::string string_attribute(const std::string& name) const;
  double double_attribute(const std::string& name) const;
  int64_t int_attribute(const std::string& name) const;
  std::vector<double> doubles_attribute(const std::string& name) const;
  std::vector<int64_t> ints_attribute(const std::string& name) const;

 private:
  std::string child_path(const std::string& name) const;
  Handle h_;
  std::string file_, path_;
};

class File {
 public:
  // Creates a file for writing, held in memory and written to `path` on close(); `path` is normally
  // the temp_path() of an AtomicOutput. `display_name` is used in messages (the final path).
  static File create(const std::filesystem::path& path, const std::string& display_name = {});
  // Opens an existing ctsurg HDF5 file read-only. InputError when missing, not a regular file, not
  // HDF5, or written without checksums (superblock version < 2).
  static File open(const std::filesystem::path& path);
  Group root() const;
  const std::string& name() const { return name_; }
  // A file from create(): writes it to its path and closes it, then checks that it opens
  // (RuntimeError naming the file when anything fails). A file from open(): closes it. Further use
  // is an error.
  void close();

 private:
  File(Handle h, std::string name, std::filesystem::path path = {})
      : h_(std::move(h)), name_(std::move(name)), write_to_(std::move(path)) {}
  Handle h_;
  std::string name_;
  std::filesystem::path write_to_;  // created files: where close() writes the image
};

}  // namespace ctsurg::h5
