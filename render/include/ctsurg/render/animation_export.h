// An animation (animated GIF or MP4) of rendered frames, through an external encoder when one is
// installed: ffmpeg for .mp4 (H.264, yuv420p) and .gif (palette from the frames), ImageMagick's convert
// for .gif without ffmpeg. The frames go through PNG files in a temporary folder; the result is written
// to a temporary name beside `path` and renamed, so a failed encoder leaves nothing.
#pragma once

#include <filesystem>
#include <vector>

#include "ctsurg/core/atomic_output.h"
#include "ctsurg/render/rgb_image.h"

namespace ctsurg {

// Which encoder would write `path` ("ffmpeg", "convert"), or "" when none is installed.
std::string animation_encoder(const std::filesystem::path& path);
// InputError(path, "suffix", ...) unless .gif or .mp4; InputError(path, "encoder", ...) when no
// encoder is installed (checked before any rendering by the tool); RuntimeError when it fails.
void check_animation_output(const std::filesystem::path& path);
// With a `unit`, the animation is added to it and committed with the pictures (atomic_output.h).
void write_animation(const std::filesystem::path& path, const std::vector<RgbImage>& frames, double frames_per_second,
                     OutputUnit* unit = nullptr);

}  // namespace ctsurg
