#include "ctsurg/render/render_pictures.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <set>
#include <sstream>

#include "ctsurg/core/error.h"
#include "ctsurg/render/image_composition.h"
#include "ctsurg/render/scene_frame.h"

namespace ctsurg {

namespace {

std::string frame_tag(int64_t f) {
  char s[32];
  std::snprintf(s, sizeof s, "%04lld", static_cast<long long>(f));
  return s;
}

std::string frame_caption(const RenderModel& m, int64_t f) {
  if (f < 0 || !m.trajectory) return "rest";
  char s[96];
  std::snprintf(s, sizeof s, "frame %lld, t = %.3f s", static_cast<long long>(f), m.trajectory->time[static_cast<std::size_t>(f)]);
  return s;
}

std::string stem(const std::string& name) {
  const auto slash = name.find_last_of('/');
  std::string s = slash == std::string::npos ? name : name.substr(slash + 1);
  const auto dot = s.find('.');
  return dot == std::string::npos ? s : s.substr(0, dot);
}

SceneFrame scene(const RenderModel& m, int64_t f) {
  return f >= 0 && m.trajectory ? trajectory_scene_frame(*m.trajectory, f) : rest_scene_frame(*m.surface);
}

// The legend of frame f's local region when it has one with any vertex in it: the run's region_nodes
// metric (ctsurg-sim's FEM local region) when recorded, else the surface vertices it covers.
std::string region_legend(const RenderModel& m, const SceneFrame& frame, int64_t f) {
  if (!frame.region || f < 0 || !m.trajectory) return {};
  int64_t vertices = 0;
  for (int64_t v = 0; v < m.trajectory->vertex_count(); ++v) vertices += frame.region[v] > 0;
  if (vertices == 0) return {};
  if (const TrajectoryMetric* nodes = m.trajectory->metric("region_nodes"))
    return "local region (" + std::to_string(std::llround(nodes->values[static_cast<std::size_t>(f)])) + " nodes)";
  return "local region (" + std::to_string(vertices) + " vertices)";
}

void check_model(const RenderModel& m) {
  if (!m.surface) throw InputError("render", "surface", "none given");
  if (m.trajectory) check_trajectory_matches_surface(*m.trajectory, m.trajectory_name, *m.surface, m.surface_name);
}

}  // namespace

std::vector<int64_t> parse_frames(const std::string& spec, int64_t frame_count, const std::string& option) {
  std::set<int64_t> out;
  std::stringstream items(spec);
  std::string item;
  const auto bad = [&](const std::string& why) {
    return InputError(option, "", "'" + spec + "': " + why + " (the trajectory has " + std::to_string(frame_count) +
                                      " frames, 0 .. " + std::to_string(frame_count - 1) + ")");
  };
  const auto number = [&](const std::string& text) {
    std::size_t used = 0;
    long long v = 0;
    try {
      v = std::stoll(text, &used);
    } catch (const std::exception&) {
      throw bad("'" + text + "' is not a frame number");
    }
    if (used != text.size()) throw bad("'" + text + "' is not a frame number");
    if (v < 0 || v >= frame_count) throw bad("frame " + text + " is out of range");
    return static_cast<int64_t>(v);
  };
  while (std::getline(items, item, ',')) {
    if (item == "rest") continue;
    if (frame_count < 1) throw bad("frames need a trajectory");
    if (item == "last") {
      out.insert(frame_count - 1);
    } else if (item == "all") {
      for (int64_t f = 0; f < frame_count; ++f) out.insert(f);
    } else if (item.find(':') != std::string::npos) {
      std::vector<std::string> parts;
      std::stringstream ps(item);
      std::string p;
      while (std::getline(ps, p, ':')) parts.push_back(p);
      if (parts.size() < 2 || parts.size() > 3) throw bad("a range is A:B or A:B:STEP");
      const int64_t a = number(parts[0]), b = number(parts[1]);
      int64_t step = 1;
      if (parts.size() == 3) {
        try {
          step = std::stoll(parts[2]);
        } catch (const std::exception&) {
          step = 0;
        }
        if (step < 1) throw bad("the step must be a positive whole number");
      }
      for (int64_t f = a; f <= b; f += step) out.insert(f);
    } else {
      out.insert(number(item));
    }
  }
  if (spec.empty()) throw bad("empty");
  return {out.begin(), out.end()};
}

void render_pictures(const RenderModel& model, const PictureRequest& request, const std::function<void(Picture&&)>& emit) {
  check_model(model);
  const bool compare = request.layout != Layout::single;
  const bool other = compare && !request.reference_is_rest;
  if (other) {
    check_model(request.reference);
    if (request.reference.trajectory) {
      for (const int64_t f : request.frames)
        if (f >= request.reference.trajectory->frame_count())
          throw InputError(request.reference.trajectory_name, "/trajectory/time",
                           "has " + std::to_string(request.reference.trajectory->frame_count()) + " frames; frame " +
                               std::to_string(f) + " was asked for");
    }
    if (request.layout == Layout::heat_map && request.reference.surface->vertex_count() != model.surface->vertex_count()) {
      throw InputError(request.reference.surface_name, "/surface/vertices",
                       "a difference heat map needs the same vertices as " + model.surface_name + " (" +
                           std::to_string(request.reference.surface->vertex_count()) + " against " +
                           std::to_string(model.surface->vertex_count()) + ")");
    }
  }
  if (request.layout == Layout::heat_map && request.heat_max_mm < 0.0)
    throw InputError("--heat-max-mm", "", "must be positive");

  // Frames to draw: trajectory frames, or the rest surface (-1).
  std::vector<int64_t> frames = request.frames;
  if (frames.empty()) frames.push_back(-1);
  if (request.turntable_steps > 0) frames.resize(1);

  // One camera framing everything drawn.
  std::vector<int64_t> real_frames;
  for (const int64_t f : frames)
    if (f >= 0) real_frames.push_back(f);
  BoundingSphere bounds = scene_bounds(*model.surface, model.trajectory, real_frames);
  if (other) {
    const BoundingSphere ref = scene_bounds(*request.reference.surface, request.reference.trajectory,
                                            request.reference.trajectory ? real_frames : std::vector<int64_t>{});
    // The smallest sphere holding both.
    const double d = (ref.centre - bounds.centre).norm();
    if (d + ref.radius > bounds.radius) {
      const double r = 0.5 * (d + ref.radius + bounds.radius);
      const Eigen::Vector3d c = d > 0.0 ? Eigen::Vector3d(bounds.centre + (r - bounds.radius) / d * (ref.centre - bounds.centre))
                                        : bounds.centre;
      bounds.centre = c, bounds.radius = r;
    }
  }

  SurfaceRenderer renderer(*model.surface, request.width, request.height, request.samples);
  std::unique_ptr<SurfaceRenderer> reference_renderer;
  if (other && request.reference.surface != model.surface)
    reference_renderer = std::make_unique<SurfaceRenderer>(*request.reference.surface, request.width, request.height, request.samples);
  SurfaceRenderer& ref_renderer = reference_renderer ? *reference_renderer : renderer;

  // Heat-map values: distance to the reference at each drawn frame; the scale is fixed for the call.
  const auto heat_values = [&](int64_t f) {
    const SceneFrame a = scene(model, f);
    const SceneFrame b = other ? scene(request.reference, request.reference.trajectory ? f : -1) : rest_scene_frame(*model.surface);
    return vertex_distances(a.vertices, b.vertices, model.surface->vertex_count());
  };
  double heat_max = request.heat_max_mm;
  if (request.layout == Layout::heat_map && !(heat_max > 0.0)) {
    for (const int64_t f : frames) {
      const std::vector<float> v = heat_values(f);
      for (const float x : v) heat_max = std::max(heat_max, double(x));
    }
    if (!(heat_max > 1e-3)) heat_max = 1e-3;
  }

  const ViewDirection& view = request.view;
  const double base_az = std::atan2(view.towards_eye.x(), -view.towards_eye.y()) * 180.0 / std::numbers::pi;
  const double base_el = std::asin(std::clamp(view.towards_eye.z(), -1.0, 1.0)) * 180.0 / std::numbers::pi;
  const int pictures = request.turntable_steps > 0 ? request.turntable_steps : static_cast<int>(frames.size());
  for (int k = 0; k < pictures; ++k) {
    const int64_t f = request.turntable_steps > 0 ? frames.front() : frames[static_cast<std::size_t>(k)];
    const ViewDirection v =
        request.turntable_steps > 0 ? view_from_angles(base_az + 360.0 * k / request.turntable_steps, base_el) : view;
    const Camera camera = frame_camera(bounds, v, request.projection, request.width, request.height);
    Picture picture;
    if (request.turntable_steps > 0) {
      char s[32];
      std::snprintf(s, sizeof s, "turn%03d", k);
      picture.tag = s;
    } else {
      picture.tag = f < 0 ? "rest" : frame_tag(f);
    }
    const SceneFrame main_scene = scene(model, f);
    const std::string main_caption =
        (other ? stem(model.trajectory ? model.trajectory_name : model.surface_name) + ": " : std::string()) +
        frame_caption(model, f);
    const std::string legend = request.style.region ? region_legend(model, main_scene, f) : std::string();
    if (request.layout == Layout::single) {
      picture.image = renderer.render(main_scene, camera, request.style);
      if (request.captions && (frames.size() > 1 || f >= 0) && request.turntable_steps == 0) draw_caption(picture.image, main_caption);
      if (request.captions && !legend.empty()) draw_region_legend(picture.image, legend, request.style.region_rgb);
    } else if (request.layout == Layout::heat_map) {
      SceneFrame s = main_scene;
      s.values = heat_values(f);
      RenderStyle style = request.style;
      style.heat_map = true;
      style.heat_max_mm = static_cast<float>(heat_max);
      // The region in white stripes over the heat colours: Turbo has no white, so no value reads as region.
      style.region_rgb[0] = style.region_rgb[1] = style.region_rgb[2] = 1.0f;
      RgbImage img = renderer.render(s, camera, style);
      if (request.captions) draw_caption(img, main_caption);
      if (request.captions && !legend.empty()) draw_region_legend(img, legend, style.region_rgb);
      const std::string title =
          other ? "difference from " + stem(request.reference.trajectory ? request.reference.trajectory_name
                                                                          : request.reference.surface_name) + " (mm)"
                : "displacement (mm)";
      picture.image = append_colour_bar(img, heat_max, title);
    } else {
      const RenderModel& ref_model = other ? request.reference : model;
      const int64_t ref_frame = other && request.reference.trajectory ? f : -1;
      SceneFrame ref_scene = scene(ref_model, ref_frame);
      const std::string ref_caption = other ? stem(ref_model.trajectory && ref_frame >= 0 ? ref_model.trajectory_name
                                                                                          : ref_model.surface_name) +
                                                  ": " + frame_caption(ref_model, ref_frame)
                                            : "rest";
      if (request.layout == Layout::side_by_side) {
        RgbImage a = ref_renderer.render(ref_scene, camera, request.style);
        RgbImage b = renderer.render(main_scene, camera, request.style);
        if (request.captions) draw_caption(a, ref_caption), draw_caption(b, main_caption);
        if (request.captions && !legend.empty()) draw_region_legend(b, legend, request.style.region_rgb);
        picture.image = side_by_side({a, b});
      } else {
        // Overlay: the reference in blue-grey, the model in tissue colour, averaged.
        RenderStyle ref_style = request.style;
        ref_style.tissue_rgb[0] = 0.35f, ref_style.tissue_rgb[1] = 0.55f, ref_style.tissue_rgb[2] = 0.9f;
        ref_style.tools = false;
        RgbImage a = ref_renderer.render(ref_scene, camera, ref_style);
        RenderStyle main_style = request.style;
        main_style.tissue_rgb[0] = 0.95f, main_style.tissue_rgb[1] = 0.55f, main_style.tissue_rgb[2] = 0.2f;
        main_style.region = false;  // averaged with the reference, stripes would only blur both shapes
        RgbImage b = renderer.render(main_scene, camera, main_style);
        picture.image = overlay(a, b);
        if (request.captions) draw_caption(picture.image, "blue: " + ref_caption + "  orange: " + main_caption);
      }
    }
    emit(std::move(picture));
  }
}

}  // namespace ctsurg
