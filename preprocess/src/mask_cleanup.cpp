// ITK is confined to this file: it takes and returns ctsurg volumes.
#include <itkBinaryBallStructuringElement.h>
#include <itkBinaryFillholeImageFilter.h>
#include <itkBinaryMorphologicalClosingImageFilter.h>
#include <itkConnectedComponentImageFilter.h>
#include <itkImage.h>
#include <itkRelabelComponentImageFilter.h>

#include "ctsurg/preprocess/mask_cleanup.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/memory_guard.h"
#include "ctsurg/preprocess/tissue_selection.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

namespace ctsurg {

namespace {

using BinaryImage = itk::Image<uint8_t, 3>;
using ComponentImage = itk::Image<uint32_t, 3>;

// A binary ITK image (1 where `keep(voxel)`), index-aligned with the volume. Geometry is left at
// ITK's defaults: the filters here only need the lattice topology.
template <class Pred>
BinaryImage::Pointer to_binary(const Volume<uint16_t>& mask, Pred keep) {
  auto image = BinaryImage::New();
  BinaryImage::SizeType size;
  for (int a = 0; a < 3; ++a) size[a] = static_cast<itk::SizeValueType>(mask.geometry.dims[a]);
  image->SetRegions(BinaryImage::RegionType(size));
  image->Allocate();
  uint8_t* out = image->GetBufferPointer();
  for (size_t n = 0; n < mask.voxels.size(); ++n) out[n] = keep(mask.voxels[n]) ? 1 : 0;
  return image;
}

void run_filter(itk::ProcessObject* filter, const char* what) {
  try {
    filter->Update();
  } catch (const itk::ExceptionObject& e) {
    throw RuntimeError(std::string("mask clean-up: ") + what + " failed: " + e.GetDescription());
  }
}

// Adds the voxels of `grown` (for `label`) where `mask` is background.
void add_where_background(Volume<uint16_t>& mask, const BinaryImage* grown, uint16_t label) {
  const uint8_t* g = grown->GetBufferPointer();
  for (size_t n = 0; n < mask.voxels.size(); ++n)
    if (g[n] && mask.voxels[n] == 0) mask.voxels[n] = label;
}

BinaryImage::Pointer close_binary(BinaryImage::Pointer image, const Volume<uint16_t>& mask, double radius_mm) {
  using Ball = itk::BinaryBallStructuringElement<uint8_t, 3>;
  Ball ball;
  Ball::SizeType radius;
  for (int a = 0; a < 3; ++a) radius[a] = static_cast<itk::SizeValueType>(std::lround(radius_mm / mask.geometry.spacing[a]));
  ball.SetRadius(radius);
  ball.CreateStructuringElement();
  auto closing = itk::BinaryMorphologicalClosingImageFilter<BinaryImage, BinaryImage, Ball>::New();
  closing->SetInput(image);
  closing->SetKernel(ball);
  closing->SetForegroundValue(1);
  closing->SetSafeBorder(true);  // pads the image so objects touching the border do not grow into it
  run_filter(closing, "closing");
  return closing->GetOutput();
}

BinaryImage::Pointer fill_binary(BinaryImage::Pointer image) {
  auto fill = itk::BinaryFillholeImageFilter<BinaryImage>::New();
  fill->SetInput(image);
  fill->SetForegroundValue(1);
  fill->SetFullyConnected(false);  // background connected through faces: thin diagonal cracks count as holes
  run_filter(fill, "hole filling");
  return fill->GetOutput();
}

// A closing radius beyond the volume closes nothing more, and its ball and the padded copies the
// filter makes (SetSafeBorder pads by the radius) grow with its cube: refused before ITK allocates.
void check_closing_radius(const ImageGeometry& g, double radius_mm) {
  if (!std::isfinite(radius_mm)) throw InputError("--closing-mm", "", "must be a finite number of mm");
  uint64_t padded = 1, ball = 1;
  for (int a = 0; a < 3; ++a) {
    const double r = std::round(radius_mm / g.spacing[a]);
    if (r > static_cast<double>(g.dims[a])) {
      throw InputError("--closing-mm", "",
                       "a radius of " + std::to_string(radius_mm) + " mm is " + std::to_string(static_cast<int64_t>(r)) +
                           " voxels along axis " + std::to_string(a) + ", more than the volume's " +
                           std::to_string(g.dims[a]) + " voxels; use at most " +
                           std::to_string(static_cast<double>(g.dims[a]) * g.spacing[a]) + " mm");
    }
    padded *= static_cast<uint64_t>(g.dims[a]) + 2 * static_cast<uint64_t>(r);
    ball *= 2 * static_cast<uint64_t>(r) + 1;
  }
  // Dilation and erosion each hold a padded input and output (uint8) besides the ball.
  check_allocation(4 * padded + ball, 1, "--closing-mm", "closing");
}

}  // namespace

Volume<uint16_t> cleanup_mask(const Volume<uint16_t>& mask, const MaskCleanupOptions& options) {
  Volume<uint16_t> out = mask;
  const auto labels = labels_present(mask);

  if (options.closing_mm > 0.0) {
    check_closing_radius(mask.geometry, options.closing_mm);
    for (int a = 0; a < 3; ++a) {
      if (std::lround(options.closing_mm / mask.geometry.spacing[a]) == 0) {
        spdlog::warn("closing radius {} mm is under half the voxel spacing {} mm along axis {}: no closing along it",
                     options.closing_mm, mask.geometry.spacing[a], a);
      }
    }
    for (const auto label : labels) {
      auto closed = close_binary(to_binary(out, [label](uint16_t v) { return v == label; }), out, options.closing_mm);
      add_where_background(out, closed.GetPointer(), label);
    }
  }
  if (options.fill_holes) {
    for (const auto label : labels) {
      auto filled = fill_binary(to_binary(out, [label](uint16_t v) { return v == label; }));
      add_where_background(out, filled.GetPointer(), label);
    }
  }
  if (options.keep_largest || options.min_component_mm3 > 0.0) {
    auto components = itk::ConnectedComponentImageFilter<BinaryImage, ComponentImage>::New();
    components->SetInput(to_binary(out, [](uint16_t v) { return v != 0; }));
    components->SetFullyConnected(true);  // 26-connectivity
    // RelabelComponentImageFilter sorts by size (largest = 1); equal sizes keep the connected
    // component filter's order, which is the raster order of each component's first voxel.
    auto relabel = itk::RelabelComponentImageFilter<ComponentImage, ComponentImage>::New();
    relabel->SetInput(components->GetOutput());
    relabel->SetSortByObjectSize(true);
    const double voxel_mm3 = mask.geometry.voxel_volume_mm3();
    if (options.min_component_mm3 > 0.0) {
      relabel->SetMinimumObjectSize(static_cast<itk::SizeValueType>(std::ceil(options.min_component_mm3 / voxel_mm3)));
    }
    run_filter(relabel, "connected components");
    const auto count = relabel->GetNumberOfObjects();
    const auto original = relabel->GetOriginalNumberOfObjects();
    const uint32_t* c = relabel->GetOutput()->GetBufferPointer();
    const uint32_t keep_max = options.keep_largest ? 1u : static_cast<uint32_t>(count);
    for (size_t n = 0; n < out.voxels.size(); ++n)
      if (c[n] == 0 || c[n] > keep_max) out.voxels[n] = 0;
    spdlog::info("connected components: {} found, {} kept", original, std::min<size_t>(keep_max, count));
  }
  return out;
}

}  // namespace ctsurg
