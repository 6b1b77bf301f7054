// Hand-written MetaImage files (text header + raw float data) for tests: lets a test build any
// header, valid or broken, without going through ITK.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace ctsurg::test {

// Writes NAME.mhd and NAME.raw in `folder`; `header_extra` overrides or adds header lines.
inline std::filesystem::path write_mhd(const std::filesystem::path& folder, const std::string& name, int nx, int ny, int nz,
                                       const std::vector<float>& values, const std::string& spacing = "1 1 1",
                                       const std::string& header_extra = "") {
  const auto mhd = folder / (name + ".mhd");
  std::ofstream h(mhd);
  h << "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n"
    << "DimSize = " << nx << " " << ny << " " << nz << "\nElementSpacing = " << spacing
    << "\nOffset = 0 0 0\nTransformMatrix = 1 0 0 0 1 0 0 0 1\n" << header_extra
    << "ElementType = MET_FLOAT\nElementDataFile = " << name << ".raw\n";
  std::ofstream r(folder / (name + ".raw"), std::ios::binary);
  r.write(reinterpret_cast<const char*>(values.data()), static_cast<std::streamsize>(values.size() * sizeof(float)));
  return mhd;
}

}  // namespace ctsurg::test
