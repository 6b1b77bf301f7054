#include "ctsurg/render/animation_export.h"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <cstdlib>
#include <unistd.h>

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

std::string quoted(const fs::path& p) {
  std::string out = "'";
  for (const char c : p.string()) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace

std::string animation_encoder(const fs::path& path) {
  const std::string s = lower_suffix(path);
  if (s == ".mp4") return on_path("ffmpeg") ? "ffmpeg" : "";
  // "convert" must be ImageMagick's (some systems have a stand-in of that name).
  if (s == ".gif")
    return on_path("ffmpeg")                                                                        ? "ffmpeg"
           : std::system("convert -version 2>/dev/null | grep -q ImageMagick >/dev/null 2>&1") == 0 ? "convert"
                                                                                                     : "";
  return "";
}

void check_animation_output(const fs::path& path) {
  const std::string s = lower_suffix(path);
  if (s != ".gif" && s != ".mp4") throw InputError(path.string(), "suffix", "an animation is a .gif or an .mp4");
  if (animation_encoder(path).empty()) {
    throw InputError(path.string(), "encoder",
                     s == ".mp4" ? "writing MP4 needs ffmpeg, which is not installed"
                                 : "writing GIF needs ffmpeg or ImageMagick's convert, neither is installed");
  }
  check_output_path(path);
}

void write_animation(const fs::path& path, const std::vector<RgbImage>& frames, double frames_per_second, OutputUnit* unit) {
  check_animation_output(path);
  if (frames.empty()) throw InputError(path.string(), "frames", "no frames to animate");
  const std::string encoder = animation_encoder(path);
  const fs::path folder = fs::temp_directory_path() / ("ctsurg-render-" + std::to_string(::getpid()));
  fs::create_directories(folder);
  struct Cleanup {
    fs::path p;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(p, ec);
    }
  } cleanup{folder};
  for (std::size_t i = 0; i < frames.size(); ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "f%05zu.png", i);
    const std::vector<uint8_t> png = encode_png(frames[i]);
    write_file_checked(folder / name, std::string_view(reinterpret_cast<const char*>(png.data()), png.size()),
                       (folder / name).string());
  }
  OutputUnit own;
  AtomicOutput& out = (unit ? *unit : own).add(path);
  std::string cmd;
  const std::string fps = std::to_string(frames_per_second);
  if (encoder == "ffmpeg" && lower_suffix(path) == ".mp4") {
    // Even sizes for yuv420p; -bitexact keeps encoder version strings out of the file.
    cmd = "ffmpeg -nostdin -loglevel error -y -framerate " + fps + " -i " + quoted(folder / "f%05d.png") +
          " -vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2' -c:v libx264 -pix_fmt yuv420p -bitexact -f mp4 " + quoted(out.temp_path());
  } else if (encoder == "ffmpeg") {
    cmd = "ffmpeg -nostdin -loglevel error -y -framerate " + fps + " -i " + quoted(folder / "f%05d.png") +
          " -vf 'split[a][b];[a]palettegen[p];[b][p]paletteuse' -f gif " + quoted(out.temp_path());
  } else {
    const int delay_cs = std::max(1, int(100.0 / frames_per_second + 0.5));
    cmd = "convert -delay " + std::to_string(delay_cs) + " -loop 0 " + quoted(folder) + "/f*.png gif:" + quoted(out.temp_path());
  }
  spdlog::debug("animation: {}", cmd);
  if (std::system(cmd.c_str()) != 0) throw RuntimeError(path.string() + ": the encoder (" + encoder + ") failed");
  if (!unit) own.commit();
}

}  // namespace ctsurg
