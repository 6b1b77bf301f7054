// ctsurg-render --surface S.h5 [--trajectory T.h5] -o OUT.png: pictures of a surface or of a
// simulation's frames (normal-mapped, offscreen OpenGL 4.5 core through OSMesa), turntables, and
// comparisons (side by side, overlay, heat map with a colour bar in mm); optionally an animation; and the
// trajectory as an animated glTF (--gltf) and a self-contained HTML page that plays it (--viewer).
#include <spdlog/spdlog.h>

#include <chrono>
#include <optional>

#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/checked_write.h"
#include "ctsurg/core/ctsurg_file.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/file_hash.h"
#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/core/tool_app.h"
#include "ctsurg/core/trajectory_file.h"
#include "ctsurg/render/animation_export.h"
#include "ctsurg/render/gltf_animation.h"
#include "ctsurg/render/html_viewer.h"
#include "ctsurg/render/render_pictures.h"
#include "ctsurg/render/trajectory_surface.h"

namespace fs = std::filesystem;

namespace {

std::string lower_suffix(const fs::path& p) {
  std::string s = p.extension().string();
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// OUT with "{}" replaced by the picture's tag.
fs::path output_name(const std::string& pattern, const std::string& tag) {
  const auto at = pattern.find("{}");
  return at == std::string::npos ? fs::path(pattern) : fs::path(pattern.substr(0, at) + tag + pattern.substr(at + 2));
}

// A trajectory records the SHA-256 of the surface it was simulated on (docs/formats.md): drawn on
// another surface, its vertices would move the wrong triangles.
void check_same_surface(const ctsurg::Trajectory& trajectory, const std::string& trajectory_path,
                        const std::string& surface_path) {
  if (trajectory.surface_sha256.empty()) return;  // simulated without a surface: the particles are drawn
  const std::string sha = ctsurg::sha256_file(surface_path);
  if (sha != trajectory.surface_sha256) {
    throw ctsurg::InputError(trajectory_path, "/trajectory@surface_sha256",
                             "the trajectory was simulated on a surface with SHA-256 " +
                                 trajectory.surface_sha256.substr(0, 12) + "... ('" + trajectory.surface_file + "'), but " +
                                 surface_path + " has " + sha.substr(0, 12) +
                                 "...: render it with the surface the scenario used");
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::string surface_path, trajectory_path, output, frames_spec, view_spec = "anterior", projection = "perspective";
  std::string layout = "single", reference = "rest", animation, gltf, viewer;
  std::string size_spec = "512";
  int samples = 4, turntable = 0;
  double heat_max = 0.0, fps = 10.0, time_scale = 1.0;
  bool no_normal_map = false, no_tools = false, no_captions = false, no_region = false;
  return ctsurg::run_tool(
      argc, argv, "ctsurg-render",
      "Render a surface file (ctsurg-surface / ctsurg-normalmap) or the frames of a trajectory simulated on it "
      "(ctsurg-sim) to PNG: offscreen OpenGL 4.5 core (OSMesa llvmpipe, no window system), per-pixel lighting with "
      "the baked normal map in tangent frames that follow the deformation, two-sided shading for cuts, tools as "
      "translucent spheres and blades, automatic framing, named views in the LPS frame. Comparisons: side by side or "
      "overlay against the rest surface or another model, or a heat map of the displacement (or the difference from "
      "another model) with a colour bar in mm. Deterministic: the same input gives the same pixels.",
      [&](CLI::App& app) {
        app.add_option("--surface,-s", surface_path,
                       "Surface file (.h5), e.g. surface_textured.h5; optional for a trajectory simulated without one "
                       "(an FEM model drawn by its tet mesh's boundary)");
        app.add_option("--trajectory,-t", trajectory_path, "Trajectory file (.h5) simulated on that surface");
        app.add_option("--output,-o", output,
                       "PNG to write; with several pictures it must contain {} (replaced by the frame number, "
                       "'rest' or 'turnNNN'). Optional with --gltf or --viewer");
        app.add_option("--frames", frames_spec,
                       "Frames: rest, last, all, N, A:B, A:B:STEP, or a comma list (default: last with a trajectory, "
                       "else rest)");
        app.add_option("--view", view_spec,
                       "anterior, posterior, left, right, superior, inferior, or AZIMUTH,ELEVATION in degrees "
                       "(0,0 = anterior, 90,0 = left)")
            ->capture_default_str();
        app.add_option("--projection", projection, "perspective or orthographic")
            ->capture_default_str()
            ->check(CLI::IsMember({"perspective", "orthographic"}));
        app.add_option("--size", size_spec, "Picture size in pixels: N (square) or WxH")->capture_default_str();
        app.add_option("--samples", samples, "Multisampling: 1 (none) or 4")->capture_default_str()->check(CLI::IsMember({1, 2, 4}));
        app.add_option("--layout", layout,
                       "single, side-by-side (reference | model), overlay (reference blue, model orange) or heat-map "
                       "(distance to the reference, mm)")
            ->capture_default_str()
            ->check(CLI::IsMember({"single", "side-by-side", "overlay", "heat-map"}));
        app.add_option("--reference", reference,
                       "What comparisons compare with: rest (the model's rest surface), a trajectory file (another "
                       "model or backend, same frame) or a surface file")
            ->capture_default_str();
        app.add_option("--heat-max-mm", heat_max, "Top of the heat map's colour bar in mm (default: the largest value)")
            ->check(CLI::PositiveNumber);
        app.add_option("--turntable", turntable, "Render this many views around the superior axis (of the first frame)")
            ->check(CLI::Range(1, 3600));
        app.add_option("--animation", animation, "Also write the pictures as an animation: .gif or .mp4 (needs ffmpeg or ImageMagick)");
        app.add_option("--fps", fps, "Animation frames per second")->capture_default_str()->check(CLI::Range(0.1, 120.0));
        app.add_option("--gltf", gltf,
                       "Also write the trajectory (--frames, default all) as an animated glTF: .glb or .gltf (+ .bin); "
                       "morph targets keyed in time, the normal map, metres +Y up; one node per topology after cuts");
        app.add_option("--viewer", viewer,
                       "Also write a self-contained HTML page (.html) that plays that glTF in a browser, offline, with "
                       "orbit controls");
        app.add_option("--time-scale", time_scale,
                       "glTF and viewer playback seconds per simulated second (e.g. 10: ten times slower)")
            ->capture_default_str()
            ->check(CLI::PositiveNumber);
        app.add_flag("--no-normal-map", no_normal_map, "Ignore the surface's normal map (geometry normals only)");
        app.add_flag("--no-tools", no_tools, "Do not draw the trajectory's spheres and blades");
        app.add_flag("--no-captions", no_captions, "No frame and model captions (and no region legend) on the pictures");
        app.add_flag("--no-region", no_region,
                     "Do not draw the FEM local region (/trajectory/surface/vertex_region: drawn by default when the "
                     "trajectory has it, hatched with its interface dark, in single, side-by-side and heat-map pictures)");
      },
      [&](const ctsurg::ToolContext&) {
        const auto start = std::chrono::steady_clock::now();
        // Arguments first, so bad usage fails before any file is read.
        if (output.empty() && gltf.empty() && viewer.empty()) {
          throw ctsurg::InputError("--output", "", "give -o OUT.png (pictures), --gltf OUT.glb or --viewer OUT.html");
        }
        const bool pictures = !output.empty();
        if (pictures && lower_suffix(output) != ".png") throw ctsurg::InputError(output, "suffix", "the output is a PNG: use .png");
        if (!pictures && !animation.empty()) throw ctsurg::InputError("--animation", "", "animates the pictures: give -o OUT.png too");
        if (!gltf.empty() && ctsurg::gltf_animation_format(gltf).empty()) {
          throw ctsurg::InputError(gltf, "suffix", "--gltf writes .glb (binary) or .gltf (JSON with a .bin beside it)");
        }
        if (!viewer.empty()) ctsurg::check_html_viewer_output(viewer);
        ctsurg::PictureRequest request;
        {
          const auto x = size_spec.find('x');
          try {
            std::size_t used = 0;
            if (x == std::string::npos) {
              request.width = request.height = std::stoi(size_spec, &used);
              if (used != size_spec.size()) throw std::invalid_argument("size");
            } else {
              request.width = std::stoi(size_spec.substr(0, x), &used);
              if (used != x) throw std::invalid_argument("size");
              request.height = std::stoi(size_spec.substr(x + 1), &used);
              if (used != size_spec.size() - x - 1) throw std::invalid_argument("size");
            }
          } catch (const std::exception&) {
            throw ctsurg::InputError("--size", "", "'" + size_spec + "' is not N or WxH");
          }
          if (request.width < 1 || request.height < 1 || request.width > 16384 || request.height > 16384) {
            throw ctsurg::InputError("--size", "", "each side must be 1 .. 16384 pixels, got " + size_spec);
          }
        }
        request.samples = samples;
        request.view = ctsurg::parse_view(view_spec);
        request.projection = projection == "orthographic" ? ctsurg::Projection::orthographic : ctsurg::Projection::perspective;
        request.layout = layout == "side-by-side" ? ctsurg::Layout::side_by_side
                         : layout == "overlay"    ? ctsurg::Layout::overlay
                         : layout == "heat-map"   ? ctsurg::Layout::heat_map
                                                  : ctsurg::Layout::single;
        request.turntable_steps = turntable;
        request.heat_max_mm = heat_max;
        request.captions = !no_captions;
        request.style.normal_map = !no_normal_map;
        request.style.tools = !no_tools;
        request.style.region = !no_region;
        if (!animation.empty()) ctsurg::check_animation_output(animation);

        // Inputs.
        std::optional<ctsurg::Trajectory> trajectory;
        if (!trajectory_path.empty()) trajectory = ctsurg::read_trajectory_file(trajectory_path);
        if (surface_path.empty() && !trajectory) throw ctsurg::InputError("--surface", "", "give a surface file, or a trajectory that has its own surface");
        // Without --surface the trajectory draws its own triangles (an FEM run without a surface file).
        const bool own_surface = surface_path.empty();
        const ctsurg::SurfaceMesh surface = own_surface ? ctsurg::trajectory_surface(*trajectory, trajectory_path)
                                                        : ctsurg::read_surface_mesh_file(surface_path);
        if (own_surface) surface_path = trajectory_path;  // names the model in captions and errors
        ctsurg::RenderModel model{&surface, surface_path, trajectory ? &*trajectory : nullptr, trajectory_path};
        std::vector<int64_t> gltf_frames;
        if (trajectory) {
          if (!own_surface) check_same_surface(*trajectory, trajectory_path, surface_path);
          ctsurg::check_trajectory_matches_surface(*trajectory, trajectory_path, surface, surface_path);
          request.frames = ctsurg::parse_frames(frames_spec.empty() ? "last" : frames_spec, trajectory->frame_count());
          // The glTF and the viewer play every frame unless --frames says which.
          gltf_frames = ctsurg::parse_frames(frames_spec.empty() ? "all" : frames_spec, trajectory->frame_count());
        } else if (!frames_spec.empty() && frames_spec != "rest") {
          throw ctsurg::InputError("--frames", "", "'" + frames_spec + "' needs --trajectory; without one only the rest surface is drawn");
        }
        if (request.style.normal_map && surface.normal_map.empty() && !own_surface) {
          spdlog::warn("{} has no normal map (/surface/normal_map): shading with its normals only (run ctsurg-normalmap "
                       "for the detail)", surface_path);
        }
        std::optional<ctsurg::SurfaceMesh> reference_surface;
        std::optional<ctsurg::Trajectory> reference_trajectory;
        if (reference != "rest") {
          if (request.layout == ctsurg::Layout::single)
            throw ctsurg::InputError("--reference", "", "is used by --layout side-by-side, overlay or heat-map");
          request.reference_is_rest = false;
          const std::string format = ctsurg::ctsurg_file_format(reference);
          if (format == "trajectory") {
            reference_trajectory = ctsurg::read_trajectory_file(reference);
            if (own_surface && !reference_trajectory->surface_file.empty()) {
              throw ctsurg::InputError(reference, "/trajectory@surface_file",
                                       "simulated on the surface '" + reference_trajectory->surface_file + "', but " +
                                           trajectory_path + " has none: compare trajectories simulated on the same model");
            }
            if (!own_surface) check_same_surface(*reference_trajectory, reference, surface_path);
            // Another run on the same surface (model B, or the GPU backend) unless its vertex count says otherwise.
            if (reference_trajectory->vertex_count() != surface.vertex_count()) {
              throw ctsurg::InputError(reference, "/trajectory/surface/rest_vertices",
                                       std::to_string(reference_trajectory->vertex_count()) + " vertices, but " +
                                           surface_path + " has " + std::to_string(surface.vertex_count()) +
                                           ": compare trajectories simulated on the same surface");
            }
            request.reference = {&surface, surface_path, &*reference_trajectory, reference};
          } else if (format == "surface_mesh") {
            reference_surface = ctsurg::read_surface_mesh_file(reference);
            request.reference = {&*reference_surface, reference, nullptr, ""};
          } else {
            throw ctsurg::InputError(reference, "/@ctsurg_format",
                                     "expected a trajectory or a surface file, found '" + (format.empty() ? std::string("none") : format) + "'");
          }
        }
        const std::size_t expected = request.turntable_steps > 0 ? static_cast<std::size_t>(request.turntable_steps)
                                                                  : std::max<std::size_t>(1, request.frames.size());
        if (pictures && expected > 1 && output.find("{}") == std::string::npos) {
          throw ctsurg::InputError(output, "name", std::to_string(expected) + " pictures: the output name needs {} for the frame number");
        }
        {
          std::vector<fs::path> outputs;
          if (pictures) outputs.push_back(output_name(output, "x"));
          if (!animation.empty()) outputs.emplace_back(animation);
          if (!gltf.empty()) {
            for (const fs::path& p : ctsurg::gltf_animation_files(gltf)) outputs.push_back(p);
          }
          if (!viewer.empty()) outputs.emplace_back(viewer);
          std::vector<fs::path> inputs{surface_path, trajectory_path};
          if (reference != "rest") inputs.emplace_back(reference);
          ctsurg::check_output_paths(outputs, inputs);  // pictures are .png, inputs .h5: a pattern cannot hit one
        }

        // Render; each picture goes to a temporary file, all (and the animation) are committed together.
        ctsurg::OutputUnit outputs;
        std::vector<std::vector<uint8_t>> animation_frames;  // PNG bytes, as written
        std::vector<fs::path> written;
        if (pictures) ctsurg::render_pictures(model, request, [&](ctsurg::Picture&& picture) {
          std::vector<uint8_t> png = ctsurg::encode_png(picture.image);
          ctsurg::AtomicOutput& out = outputs.add(output_name(output, picture.tag));
          ctsurg::write_file_checked(out.temp_path(),
                                     std::string_view(reinterpret_cast<const char*>(png.data()), png.size()),
                                     out.path().string());
          written.push_back(out.path());
          if (!animation.empty()) animation_frames.push_back(std::move(png));
        });
        if (!animation.empty()) ctsurg::write_animation_png(animation, animation_frames, fps, &outputs);
        if (!gltf.empty() || !viewer.empty()) {
          // The trajectory's frames (none with --frames rest: the surface alone), as morph targets.
          const bool animated = trajectory && !gltf_frames.empty();
          ctsurg::GltfAnimationOptions options;
          options.frames = gltf_frames;
          options.time_scale = time_scale;
          options.normal_map = !no_normal_map;
          options.trajectory_name = trajectory_path;
          const ctsurg::Trajectory* played = animated ? &*trajectory : nullptr;
          const auto gltf_start = std::chrono::steady_clock::now();
          ctsurg::GltfAnimationSummary summary;
          std::string glb;
          if (!gltf.empty()) {
            glb = ctsurg::add_gltf_animation(outputs, gltf, surface, played, options, &summary);
            spdlog::info("{}: {} frame{}, {} morph target{} ({} sparse or empty accessors), {} node{}: {:.1f} MB in {:.2f} s",
                         gltf, summary.frames, summary.frames == 1 ? "" : "s", summary.morph_targets,
                         summary.morph_targets == 1 ? "" : "s", summary.sparse_targets, summary.nodes,
                         summary.nodes == 1 ? "" : "s", static_cast<double>(summary.bytes) / 1e6,
                         std::chrono::duration<double>(std::chrono::steady_clock::now() - gltf_start).count());
          }
          if (!viewer.empty()) {
            // The page embeds a .glb: the one just written, or one made for it.
            if (glb.empty() || ctsurg::gltf_animation_format(gltf) != "glb") {
              glb = std::move(ctsurg::export_gltf_animation(fs::path(viewer).replace_extension(".glb"), surface, played, options).front().second);
            }
            ctsurg::HtmlViewerOptions page;
            page.title = fs::path(animated ? trajectory_path : surface_path).filename().string();
            page.time_offset_s = animated ? trajectory->time[static_cast<std::size_t>(gltf_frames.front())] : 0.0;
            page.time_scale = time_scale;
            page.time_end_s = animated ? trajectory->time[static_cast<std::size_t>(gltf_frames.back())] : 0.0;
            const std::size_t bytes = ctsurg::add_html_viewer(outputs, viewer, glb, page);
            spdlog::info("{}: an HTML page playing the glTF ({}): {:.1f} MB", viewer, ctsurg::html_viewer_library(),
                         static_cast<double>(bytes) / 1e6);
          }
        }
        outputs.commit();
        std::string also = animation;
        for (const std::string& o : {gltf, viewer})
          if (!o.empty()) also += (also.empty() ? "" : ", ") + o;
        if (pictures) {
          spdlog::info("wrote {} picture{} ({}{}) in {:.2f} s", written.size(), written.size() == 1 ? "" : "s",
                       written.size() == 1 ? written.front().string() : output, also.empty() ? "" : ", " + also,
                       std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        } else {
          spdlog::info("wrote {} in {:.2f} s", also, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        }
      });
}
