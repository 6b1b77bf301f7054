#include "ctsurg/render/animation_export.h"

#include <spdlog/spdlog.h>
#include <sys/wait.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <utility>

#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/checked_write.h"
#include "ctsurg/core/error.h"

namespace fs = std::filesystem;

namespace ctsurg {

namespace {

std::string lower_suffix(const fs::path& p) {
  std::string s = p.extension().string();
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool on_path(const std::string& program) {
  return std::system(("command -v " + program + " >/dev/null 2>&1").c_str()) == 0;
}

// A real ImageMagick prints "Version: ImageMagick 6.9..." first; a stand-in of that name may mention
// ImageMagick elsewhere ("ImageMagick is not installed here"), so the match is anchored.
bool imagemagick_convert() {
  return std::system("convert -version 2>/dev/null | grep -q '^Version: ImageMagick'") == 0;
}

std::string quoted(const fs::path& p) {
  std::string out = "'";
  for (const char c : p.string()) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// The last `limit` characters of a small text file ("" when it cannot be read).
std::string tail_of(const fs::path& path, std::size_t limit) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  std::string s = ss.str();
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == ' ')) s.pop_back();
  return s.size() > limit ? "..." + s.substr(s.size() - limit) : s;
}

// A temporary folder of its own (mkdtemp), removed with everything in it when this goes out of scope.
struct FrameFolder {
  fs::path path;
  FrameFolder() {
    std::string name = (fs::temp_directory_path() / "ctsurg-animation-XXXXXX").string();
    if (::mkdtemp(name.data()) == nullptr)
      throw RuntimeError(name + ": cannot create a temporary folder for the frames: " + std::strerror(errno));
    path = name;
  }
  ~FrameFolder() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  FrameFolder(const FrameFolder&) = delete;
  FrameFolder& operator=(const FrameFolder&) = delete;
};

}  // namespace

std::string animation_encoder(const fs::path& path) {
  const std::string s = lower_suffix(path);
  // ffmpeg first for GIF too: its palette is computed from all frames (palettegen), and its output is
  // byte-identical between runs; convert only when ffmpeg is missing.
  if (s == ".mp4") return on_path("ffmpeg") ? "ffmpeg" : "";
  if (s == ".gif") return on_path("ffmpeg") ? "ffmpeg" : imagemagick_convert() ? "convert" : "";
  return "";
}

void check_animation_output(const fs::path& path) {
  const std::string s = lower_suffix(path);
  if (s != ".gif" && s != ".mp4") {
    throw InputError(path.string(), "suffix",
                     "an animation is a .gif or an .mp4, got '" + (s.empty() ? std::string("no suffix") : s) + "'");
  }
  if (animation_encoder(path).empty()) {
    throw InputError(path.string(), "encoder",
                     s == ".mp4" ? "writing MP4 needs ffmpeg, which is not installed (scripts/install-deps.sh installs it)"
                                 : "writing GIF needs ffmpeg or ImageMagick's convert, neither is installed "
                                   "(scripts/install-deps.sh installs ffmpeg)");
  }
  check_output_path(path);
}

std::string animation_command(const std::string& encoder, const fs::path& frame_pattern, const fs::path& output,
                              double frames_per_second, bool mp4) {
  char fps[32];
  std::snprintf(fps, sizeof fps, "%.6g", frames_per_second);
  if (encoder == "ffmpeg") {
    // No banner, no progress line, errors only (they go to a log that the error message quotes);
    // +bitexact keeps the libavformat/libavcodec version strings out of the file, -map_metadata -1
    // any metadata, so the same frames give the same bytes with the same ffmpeg.
    std::string cmd = "ffmpeg -nostdin -hide_banner -nostats -loglevel error -y -framerate " + std::string(fps) +
                      " -start_number 0 -i " + quoted(frame_pattern) + " -map_metadata -1 -fflags +bitexact ";
    if (mp4) {
      // H.264 in yuv420p (what browsers and players take) needs even sides: a black row or column is
      // added when a side is odd. RGB -> BT.709 limited range, tagged so; accurate_rnd+bitexact makes
      // swscale give the same YUV with and without SIMD. A fixed thread count: x264 is deterministic
      // for a given thread count, and the automatic one depends on the machine's cores.
      cmd += "-vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2,scale=out_color_matrix=bt709:out_range=tv:flags=accurate_rnd+bitexact,"
             "format=yuv420p' -c:v libx264 -preset medium -crf 18 -threads 4 -flags:v +bitexact "
             "-colorspace bt709 -color_primaries bt709 -color_trc bt709 -color_range tv -movflags +faststart -f mp4 ";
    } else {
      // One 256-colour palette from all frames (no colour reserved for transparency: the frames are
      // opaque), Floyd-Steinberg-like error diffusion; loops forever.
      cmd += "-vf 'split[a][b];[a]palettegen=stats_mode=full:reserve_transparent=0[p];[b][p]paletteuse=dither=sierra2_4a' "
             "-loop 0 -f gif ";
    }
    return cmd + quoted(output);
  }
  // ImageMagick: delays in hundredths of a second.
  const int delay_cs = std::max(1, int(100.0 / frames_per_second + 0.5));
  return "convert -delay " + std::to_string(delay_cs) + " -loop 0 " + quoted(frame_pattern.parent_path()) +
         "/f*.png gif:" + quoted(output);
}

void write_animation(const fs::path& path, const std::vector<RgbImage>& frames, double frames_per_second, OutputUnit* unit) {
  std::vector<std::vector<uint8_t>> png_frames;
  png_frames.reserve(frames.size());
  for (const RgbImage& f : frames) png_frames.push_back(encode_png(f));
  write_animation_png(path, png_frames, frames_per_second, unit);
}

void write_animation_png(const fs::path& path, const std::vector<std::vector<uint8_t>>& png_frames,
                         double frames_per_second, OutputUnit* unit) {
  check_animation_output(path);
  if (png_frames.empty()) throw InputError(path.string(), "frames", "no frames to animate");
  if (!(frames_per_second > 0.0)) throw InputError(path.string(), "fps", "the frame rate must be positive");
  // Width and height from each PNG's IHDR chunk (bytes 16..23, big-endian; PNG spec 11.2.2).
  const auto size_of = [&](const std::vector<uint8_t>& png) {
    static const uint8_t signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (png.size() < 24 || std::memcmp(png.data(), signature, 8) != 0 || std::memcmp(png.data() + 12, "IHDR", 4) != 0)
      throw InputError(path.string(), "frames", "a frame is not a PNG");
    const auto be32 = [&](std::size_t at) {
      return uint32_t(png[at]) << 24 | uint32_t(png[at + 1]) << 16 | uint32_t(png[at + 2]) << 8 | uint32_t(png[at + 3]);
    };
    return std::pair<uint32_t, uint32_t>(be32(16), be32(20));
  };
  const auto size = size_of(png_frames.front());
  for (const auto& png : png_frames) {
    if (size_of(png) != size)
      throw InputError(path.string(), "frames", "the frames of an animation must all have the same size");
  }
  const std::string encoder = animation_encoder(path);
  const FrameFolder folder;
  for (std::size_t i = 0; i < png_frames.size(); ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "f%05zu.png", i);
    const auto& png = png_frames[i];
    write_file_checked(folder.path / name, std::string_view(reinterpret_cast<const char*>(png.data()), png.size()),
                       (folder.path / name).string());
  }
  OutputUnit own;
  AtomicOutput& out = (unit ? *unit : own).add(path);
  const fs::path log = folder.path / "encoder.log";
  const std::string cmd = animation_command(encoder, folder.path / "f%05d.png", out.temp_path(), frames_per_second,
                                            lower_suffix(path) == ".mp4") +
                          " >" + quoted(log) + " 2>&1";
  spdlog::info("encoding {} frame{} to {} with {}", png_frames.size(), png_frames.size() == 1 ? "" : "s", path.string(), encoder);
  spdlog::debug("animation: {}", cmd);
  const int status = std::system(cmd.c_str());
  if (status != 0) {
    std::error_code ec;
    fs::remove(out.temp_path(), ec);  // AtomicOutput removes it too; do not leave a partial file meanwhile
    const std::string why = status == -1                                  ? std::string("could not be started")
                            : WIFEXITED(status) && WEXITSTATUS(status) == 127 ? std::string("was not found")
                            : WIFEXITED(status)   ? "exited with status " + std::to_string(WEXITSTATUS(status))
                            : WIFSIGNALED(status) ? "was killed by signal " + std::to_string(WTERMSIG(status))
                                                  : "failed";
    const std::string said = tail_of(log, 2000);
    throw RuntimeError(path.string() + ": the encoder (" + encoder + ") " + why + (said.empty() ? "" : ": " + said));
  }
  if (!unit) own.commit();
}

}  // namespace ctsurg
