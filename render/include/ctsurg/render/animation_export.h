// An animation (animated GIF or MP4) of rendered frames, through an external encoder when one is
// installed: ffmpeg for .mp4 (H.264, yuv420p) and .gif (palette from the frames), ImageMagick's convert
// for .gif without ffmpeg. The frames go through PNG files in a temporary folder; the result is written
// to a temporary name beside `path` and renamed, so a failed encoder leaves nothing.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "ctsurg/core/atomic_output.h"
#include "ctsurg/render/rgb_image.h"

namespace ctsurg {

// Which encoder would write `path` ("ffmpeg", "convert"), or "" when none is installed.
std::string animation_encoder(const std::filesystem::path& path);
// InputError(path, "suffix", ...) unless .gif or .mp4; InputError(path, "encoder", ...) when no
// encoder is installed (checked before any rendering by the tool); RuntimeError when it fails.
void check_animation_output(const std::filesystem::path& path);
// The shell command that encodes the PNG frames `frame_pattern` ("DIR/f%05d.png", numbered from 0) into
// `output` with `encoder` (see animation_encoder); `mp4` picks H.264 over GIF. Shown for docs and tests.
std::string animation_command(const std::string& encoder, const std::filesystem::path& frame_pattern,
                              const std::filesystem::path& output, double frames_per_second, bool mp4);
// Writes `frames` (all the same size, any size: an odd side of an MP4 gets one black row or column,
// since yuv420p needs even sides) at `frames_per_second` (> 0) to `path` (.gif or .mp4). With a
// `unit`, the animation is added to it and committed with the pictures (atomic_output.h); without,
// it is committed here. InputError as check_animation_output, or naming "frames"/"fps"; RuntimeError
// quoting the encoder's exit status and the end of its error output when it fails (no file is left).
void write_animation(const std::filesystem::path& path, const std::vector<RgbImage>& frames, double frames_per_second,
                     OutputUnit* unit = nullptr);
// The same with frames already encoded by encode_png (what ctsurg-render writes anyway: encoding them
// again cost more than the video encoding itself, and PNGs hold a long animation in less memory).
void write_animation_png(const std::filesystem::path& path, const std::vector<std::vector<uint8_t>>& png_frames,
                         double frames_per_second, OutputUnit* unit = nullptr);

}  // namespace ctsurg
