// What ctsurg verifies in a DICOM file before GDCM reads it. GDCM allocates the length an element
// declares before reading its value, so a 1.5 KB file whose header claims a 3 GB element made the
// importer allocate (and zero) 3 GB (found by tests/fuzz/fuzz_dicom_folder.cpp). Every element of a Part 10
// file is walked (PS3.5 7.1: explicit or implicit VR, little or big endian; sequences and items of
// undefined length down to 64 levels, PS3.5 7.5; encapsulated pixel data as items, PS3.5 A.4) and
// each defined length must fit in the bytes left in the file.
#pragma once

#include <filesystem>

namespace ctsurg {

// InputError(file, "(gggg,eeee)", ...) naming the first element whose declared length runs past the
// end of the file (or whose nesting is deeper than 64). Files without the Part 10 marker ("DICM" at
// byte 128) and deflated transfer syntaxes are left to GDCM.
void check_dicom_element_lengths(const std::filesystem::path& file);

}  // namespace ctsurg
