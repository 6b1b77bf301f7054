// Hand-made 3D Slicer segmentation files (.seg.nrrd) for tests: a NRRD header with Segment<k>_
// fields, attached raw uint8 voxels, one layer (3D) or several (4D, a "list" first axis).
#pragma once

#include <spdlog/fmt/fmt.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace ctsurg::test {

struct SegNrrdSegment {
  std::string name;
  int layer = 0;
  int value = 1;
  bool write_label_value = true;
};

struct SegNrrd {
  std::array<int64_t, 3> dims{4, 3, 2};
  std::array<double, 3> spacing{1.0, 1.0, 1.0};
  std::array<double, 3> origin{0.0, 0.0, 0.0};
  std::string space = "left-posterior-superior";
  int layers = 1;
  std::vector<SegNrrdSegment> segments;
  std::vector<uint8_t> voxels;  // layers fastest, then i, j, k; layers * dims product values
  std::vector<std::string> extra_lines;

  uint8_t& at(int layer, int64_t i, int64_t j, int64_t k) {
    return voxels[static_cast<std::size_t>(layer + layers * (i + dims[0] * (j + dims[1] * k)))];
  }
  void allocate() { voxels.assign(static_cast<std::size_t>(layers * dims[0] * dims[1] * dims[2]), 0); }

  void write(const std::filesystem::path& path) const {
    std::string h = "NRRD0004\n# Complete NRRD file format specification at:\n# http://teem.sourceforge.net/nrrd/format.html\n"
                    "type: unsigned char\n";
    const bool four = layers > 1;
    h += fmt::format("dimension: {}\nspace: {}\n", four ? 4 : 3, space);
    h += four ? fmt::format("sizes: {} {} {} {}\n", layers, dims[0], dims[1], dims[2])
              : fmt::format("sizes: {} {} {}\n", dims[0], dims[1], dims[2]);
    h += fmt::format("space directions: {}({},0,0) (0,{},0) (0,0,{})\n", four ? "none " : "", spacing[0], spacing[1],
                     spacing[2]);
    h += four ? "kinds: list domain domain domain\n" : "kinds: domain domain domain\n";
    h += fmt::format("encoding: raw\nspace origin: ({},{},{})\n", origin[0], origin[1], origin[2]);
    h += "Segmentation_MasterRepresentation:=Binary labelmap\n";
    for (std::size_t k = 0; k < segments.size(); ++k) {
      const auto& s = segments[k];
      h += fmt::format("Segment{}_Color:=0.5 0.7 0.2\nSegment{}_Extent:=0 {} 0 {} 0 {}\nSegment{}_ID:=Segment_{}\n", k, k,
                       dims[0] - 1, dims[1] - 1, dims[2] - 1, k, k + 1);
      if (s.write_label_value) h += fmt::format("Segment{}_LabelValue:={}\n", k, s.value);
      h += fmt::format("Segment{}_Layer:={}\nSegment{}_Name:={}\n", k, s.layer, k, s.name);
    }
    for (const auto& l : extra_lines) h += l + "\n";
    h += "\n";
    std::ofstream out(path, std::ios::binary);
    out << h;
    out.write(reinterpret_cast<const char*>(voxels.data()), static_cast<std::streamsize>(voxels.size()));
  }
};

}  // namespace ctsurg::test
