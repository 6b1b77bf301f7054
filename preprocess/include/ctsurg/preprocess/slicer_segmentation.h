// 3D Slicer segmentation files (.seg.nrrd) as label volumes.
//
// A .seg.nrrd is a NRRD image with per-segment key/value fields (Slicer developer guide,
// "Segmentation labelmap file format"): Segment<k>_ID, _Name, _LabelValue, _Layer, _Extent, _Color,
// ... for k = 0 .. #segments - 1. The voxels are one 3D layer (sizes i j k) or several layers
// (4D, a first axis of kind "list": sizes L i j k); segment k is the voxels of layer
// Segment<k>_Layer whose value is Segment<k>_LabelValue. Slicer puts overlapping segments on
// different layers; ctsurg needs one label per voxel, so the layers are merged and a voxel in two
// segments is refused.
//
// The NRRD is parsed here (not by ITK, which reads no 4D label layers): attached data only,
// encodings raw, gzip and ascii, integer voxel types of 1 to 4 bytes in either byte order, space
// left-posterior-superior (LPS) or right-anterior-superior (RAS, converted to LPS).
#pragma once

#include "ctsurg/core/volume.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace ctsurg {

struct SlicerSegment {
  int index = 0;                 // k of the Segment<k>_ fields
  std::string id;                // Segment<k>_ID
  std::string name;              // Segment<k>_Name
  int layer = 0;                 // Segment<k>_Layer
  int64_t label_value = 0;       // Segment<k>_LabelValue: the voxel value in its layer
  uint16_t label = 0;            // the label of the merged volume (label_value unless renumbered)
  std::array<double, 3> color{0.5, 0.5, 0.5};  // Segment<k>_Color, RGB in [0, 1]
};

struct SlicerSegmentation {
  Volume<uint16_t> labels;             // merged layers on the file's lattice (LPS mm, x fastest), 0 = none
  std::vector<SlicerSegment> segments; // in file order
  // Segment names by merged label.
  std::map<uint16_t, std::string> label_names() const;
};

// True when `path`'s name ends with ".seg.nrrd" (case-insensitive).
bool is_slicer_segmentation_file(const std::filesystem::path& path);

// Reads a .seg.nrrd. InputError(path, field, ...) naming the NRRD field or the Segment<k>_ field for
// a malformed header, an unsupported type/encoding/space, a missing segment field (ID, Name,
// LabelValue, Layer), a layer or label value out of range, two segments with one label value in
// one layer, a voxel value that is no segment's, truncated data, and overlapping segments (how many
// voxels, which segments). Segments in different layers with the same label value get the next free
// label; each renumbering is reported in `warnings` (optional).
SlicerSegmentation read_slicer_segmentation(const std::filesystem::path& path,
                                            std::vector<std::string>* warnings = nullptr);

// Puts a segmentation onto the CT's lattice. Slicer crops a segmentation to its segments, so its
// lattice may be a box of the CT's voxels: the same spacing and direction (within 1e-3 mm over the
// box) with the origin on a CT voxel centre. Anything else is InputError(file, "space directions" /
// "space origin" / "sizes", ...) giving both geometries; a box reaching outside the CT is refused
// when a labelled voxel lies outside it.
//   seg     labels on the file's lattice
//   ct      the CT's lattice
// Returns the labels on `ct` (0 outside the box).
Volume<uint16_t> place_on_lattice(const Volume<uint16_t>& seg, const ImageGeometry& ct, const std::string& file);

}  // namespace ctsurg
