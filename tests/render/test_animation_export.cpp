// animation_export.h: the encoder chosen by suffix, byte-identical reruns, odd sides padded for
// yuv420p, and refusals (unknown suffix, frames of two sizes, no frame rate, a failed encoder) that leave
// no file.
// Needs ffmpeg and ffprobe (scripts/install-deps.sh; CI has them): their absence fails, never skips.
#include "ctsurg/render/animation_export.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

#include "ctsurg/core/error.h"
#include "test_support.h"

namespace fs = std::filesystem;
using ctsurg::test::TempDir;

namespace {

#define CTSURG_REQUIRE_FFMPEG()                                                                                 \
  ASSERT_EQ(ctsurg::test::run_shell("command -v ffmpeg && command -v ffprobe").exit_code, 0)                    \
      << "ffmpeg and ffprobe are not installed: run scripts/install-deps.sh"

// A square moving across a gradient: every frame differs, and the palette has more than 256 colours.
std::vector<ctsurg::RgbImage> moving_square(int width, int height, int count) {
  std::vector<ctsurg::RgbImage> frames;
  for (int f = 0; f < count; ++f) {
    ctsurg::RgbImage img(width, height);
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        uint8_t* p = img.pixel(x, y);
        const bool square = x >= 3 * f && x < 3 * f + 8 && y >= 4 && y < 12;
        p[0] = square ? 255 : static_cast<uint8_t>(255 * x / width);
        p[1] = square ? 255 : static_cast<uint8_t>(255 * y / height);
        p[2] = static_cast<uint8_t>(40 * f);
      }
    frames.push_back(std::move(img));
  }
  return frames;
}

std::string probe(const fs::path& file) {
  return ctsurg::test::run_shell("ffprobe -v error -count_frames -select_streams v:0 -show_entries "
                                 "stream=codec_name,pix_fmt,width,height,nb_read_frames -of csv=p=0 '" +
                                 file.string() + "'")
      .output;
}

}  // namespace

TEST(AnimationExport, FfmpegIsPreferredAndTheSameFramesGiveTheSameBytes) {
  CTSURG_REQUIRE_FFMPEG();
  EXPECT_EQ(ctsurg::animation_encoder("a.gif"), "ffmpeg");
  EXPECT_EQ(ctsurg::animation_encoder("a.MP4"), "ffmpeg");
  EXPECT_EQ(ctsurg::animation_encoder("a.avi"), "");
  TempDir dir;
  const auto frames = moving_square(33, 25, 6);  // odd sides
  for (const std::string suffix : {".mp4", ".gif"}) {
    ctsurg::write_animation(dir / ("a" + suffix), frames, 12.0);
    ctsurg::write_animation(dir / ("b" + suffix), frames, 12.0);
    const std::string a = ctsurg::test::read_bytes(dir / ("a" + suffix));
    EXPECT_FALSE(a.empty());
    EXPECT_TRUE(a == ctsurg::test::read_bytes(dir / ("b" + suffix))) << suffix << " differs between two runs";
    // yuv420p needs even sides: one black column and row added; a GIF keeps the size.
    EXPECT_EQ(probe(dir / ("a" + suffix)), suffix == ".mp4" ? "h264,34,26,yuv420p,6\n" : "gif,33,25,bgra,6\n");
  }
  // Only the two animations and their reruns: no frames or temporary names left beside them.
  EXPECT_EQ(ctsurg::test::files_in(dir.path()).size(), 4u);
}

TEST(AnimationExport, RefusalsNameTheFieldAndAFailedEncoderLeavesNothing) {
  CTSURG_REQUIRE_FFMPEG();
  TempDir dir;
  const auto frames = moving_square(16, 16, 2);
  try {
    ctsurg::write_animation(dir / "a.webm", frames, 10.0);
    ADD_FAILURE() << "a .webm was accepted";
  } catch (const ctsurg::InputError& e) {
    EXPECT_EQ(e.field(), "suffix") << e.what();
  }
  std::vector<ctsurg::RgbImage> mixed = frames;
  mixed.push_back(ctsurg::RgbImage(8, 8));
  try {
    ctsurg::write_animation(dir / "a.gif", mixed, 10.0);
    ADD_FAILURE() << "frames of two sizes were accepted";
  } catch (const ctsurg::InputError& e) {
    EXPECT_EQ(e.field(), "frames") << e.what();
  }
  EXPECT_THROW(ctsurg::write_animation(dir / "a.mp4", frames, 0.0), ctsurg::InputError);
  // An encoder that writes half a file and fails: RuntimeError with its exit status and what it said;
  // neither the partial file nor a temporary name is left.
  const fs::path bin = dir / "bin";
  fs::create_directory(bin);
  {
    std::ofstream fake(bin / "ffmpeg");
    fake << "#!/bin/sh\nfor a; do last=$a; done\necho partial > \"$last\"\necho 'fake ffmpeg: disk on fire' >&2\nexit 3\n";
  }
  fs::permissions(bin / "ffmpeg", fs::perms::owner_all);
  const std::string path = std::getenv("PATH") ? std::getenv("PATH") : "/usr/bin:/bin";
  ::setenv("PATH", (bin.string() + ":" + path).c_str(), 1);
  for (const std::string name : {"out/a.mp4", "out/a.gif"}) {
    fs::create_directories(dir / "out");
    try {
      ctsurg::write_animation(dir / name, frames, 10.0);
      ADD_FAILURE() << name << ": the failed encoder was not noticed";
    } catch (const ctsurg::RuntimeError& e) {
      EXPECT_NE(std::string(e.what()).find("the encoder (ffmpeg) exited with status 3: fake ffmpeg: disk on fire"),
                std::string::npos)
          << e.what();
    }
    EXPECT_TRUE(ctsurg::test::files_in(dir / "out").empty()) << name;
  }
  ::setenv("PATH", path.c_str(), 1);
}
