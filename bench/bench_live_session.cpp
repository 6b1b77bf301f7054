// Live sessions on the bundled heart (issue 22, performance): for each model the heart scenarios use, a
// LiveSession built from the scenario without its own tools, driven exactly as ctsurg-live drives it: a
// loop of ticks, each applying the client messages that have arrived (JSON text through
// parse_live_message, as the server gets them; each move travelling over a tick,
// LiveSession::set_move_ramp_s, as the server sets it), then session.advance(1/60) (1/60 s of simulated time
// asked for within at most 1/60 s of wall time), then the frame the server sends
// (encode_live_frame(live_frame_of(...)): the positions, with the triangles when the topology changed).
//
// The user (messages timed in wall seconds from the first tick, a mouse sending 60 moves a second):
//   0 .. 3 s     grab (8 mm) begun at the apex's surface vertex (the surface vertex nearest the point at
//                fractions (0.75, 0, 0.2) of the rest box: heart_grab.yaml's at_fraction), dragged 25 mm
//                along heart_grab's pull direction (10, -25, -10), a move every 1/60 s;
//   3 .. 3.5 s   held; ended at 3.5 s;
//   3.5 .. 4.5 s a cut (20 mm edge along +y, into the anterior wall) drawn 40 mm from inferior to superior
//                across the surface, heart_cut.yaml's incision, a move every 1/60 s; ended at 4.5 s. The steady drag is measured from 0.5 s (after the grab's
//                begin and its factorisation) to 3 s.
//
// Each model runs the script twice, on a fresh session each time:
//   paced    as the server: a tick every 1/60 s of wall time paced by the server's LiveClock (live_clock.h:
//            simulated time owed at real time, a backlog of at most 0.1 s caught up; a quasi-static
//            frame longer than a tick is paid back by ticks that do not advance; the loop sleeps when a tick ends early, a
//            late tick is followed at once), a picture when something changed. Real-time factor =
//            simulated s / wall s; pictures/s = pictures / wall s; per-picture time = message handling +
//            advance + frame.
//   unpaced  the loop never sleeps: how many pictures a second the server could send (the simulation
//            then runs ahead of the wall clock where it is faster than real time).
// Bytes per frame: positions only (56 + 12 V) and with the triangles (+ 12 F, the first frame and after
// a cut); the largest frame seen. Steps: the engine's steps over the paced run and per simulated second.
//
//   bench_live_session --heart DIR [--scenarios DIR] [--cases a,b,...] [--threads N] [--backend cpu|cuda|auto]
//                      [--markdown] [--verbose]
//
// DIR holds the demo's heart inputs (grid.h5, surface_textured.h5, tetmesh.h5: build/demo/heart, made by
// `make -f scripts/Makefile demo`, or by bench/run.sh live). Cases: grid (heart_grab.yaml: the implicit
// spring grid), explicit (heart_explicit_grab.yaml), fem_static (heart_fem_grab.yaml: Neo-Hookean static,
// Newton to the relative 1e-8), fem_static_mm (Newton to solver.tolerance_mm 0.05), fem_static_qn (quasi-Newton to
// 0.05 mm: solver.nonlinear: quasi_newton, fem_static_solver.h),
// fem_dynamic (heart_fem_cut.yaml: Neo-Hookean explicit dynamics), fem_linear (heart_fem_grab.yaml with
// material.law: linear, the FEM-speed work's fastest model within 1 mm, docs/accuracy.md), fem_local
// (heart_fem_local.yaml: Neo-Hookean in a 20 mm local region), live (heart_live.yaml: the scenario
// ctsurg-live opens, Neo-Hookean static by quasi-Newton, a frame per 1/30 s). Prints one markdown row per case
// (--markdown: with the table's header). Exit 2 for bad arguments or inputs, 1 when a case fails.
#include "ctsurg/core/error.h"
#include "ctsurg/sim/live/live_clock.h"
#include "ctsurg/sim/live/live_protocol.h"
#include "ctsurg/sim/live/live_session.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;
using namespace ctsurg;
using namespace ctsurg::sim;
using Clock = std::chrono::steady_clock;

namespace {

bool g_verbose = false;                   // --verbose: a line per 10 ticks on stderr
constexpr double kTick = 1.0 / 60;        // s: the server's tick and the mouse's move interval
constexpr double kDragEnd = 3.0;          // s (wall): the grab's drag ends
constexpr double kDragFrom = 0.5;         // s (wall): the steady drag measured from here (after the grab's begin)
constexpr double kGrabEnd = 3.5;          // s: the grab is released, the cut begins
constexpr double kCutEnd = 4.5;           // s: the cut ends, and the script
constexpr double kDragMm = 25;            // mm
constexpr double kGrabRadiusMm = 8;
constexpr std::array<double, 3> kPullDirection{10, -25, -10};  // heart_grab.yaml's offset
constexpr std::array<double, 3> kCutFrom{25, -234, 615}, kCutTo{25, -234, 655}, kBladeEdge{0, 20, 0};  // heart_cut.yaml

struct Case {
  std::string name, label, scenario;
  std::string material_law;  // overrides material.law when not empty
  std::string nonlinear;     // overrides solver.nonlinear when not empty
  double tolerance_mm = 0;   // sets solver.tolerance_mm when > 0
};

const std::vector<Case> kCases = {
    {"grid", "spring grid (heart_grab)", "heart_grab.yaml", "", "", 0},
    {"explicit", "explicit springs (heart_explicit_grab)", "heart_explicit_grab.yaml", "", "", 0},
    {"fem_static", "FEM Neo-Hookean static, Newton (heart_fem_grab)", "heart_fem_grab.yaml", "", "", 0},
    {"fem_static_mm", "FEM Neo-Hookean static, Newton to 0.05 mm (heart_fem_grab, solver.tolerance_mm: 0.05)", "heart_fem_grab.yaml", "", "",
     0.05},
    {"fem_static_qn", "FEM Neo-Hookean static, quasi-Newton to 0.05 mm (heart_fem_grab, solver: {nonlinear: quasi_newton, tolerance_mm: 0.05})",
     "heart_fem_grab.yaml", "", "quasi_newton", 0.05},
    {"fem_dynamic", "FEM Neo-Hookean dynamic (heart_fem_cut)", "heart_fem_cut.yaml", "", "", 0},
    {"fem_linear", "FEM linear static (heart_fem_grab, material.law: linear)", "heart_fem_grab.yaml", "linear", "", 0},
    {"fem_local", "FEM Neo-Hookean static, 20 mm local region (heart_fem_local)", "heart_fem_local.yaml", "", "", 0},
    {"live", "FEM Neo-Hookean static, quasi-Newton to 0.05 mm, a frame per 1/30 s (heart_live: ctsurg-live's scenario)", "heart_live.yaml", "", "", 0},
};

// A timed client message.
struct Message {
  double at_s = 0;
  std::string text;
};

std::string vec_text(const std::array<double, 3>& v) {
  char s[128];
  std::snprintf(s, sizeof s, "[%.17g, %.17g, %.17g]", v[0], v[1], v[2]);
  return s;
}

// The user's messages (see the header), with the grab starting at `apex` (LPS mm). Ids: the grab 0, the
// cut 1 (begin order); seq counts the messages from 1.
std::vector<Message> user_script(const std::array<double, 3>& apex) {
  std::vector<Message> script;
  uint32_t seq = 0;
  const auto add = [&](double at, const std::string& body) {
    script.push_back({at, "{" + body + ", \"seq\": " + std::to_string(++seq) + "}"});
  };
  const double n = std::sqrt(kPullDirection[0] * kPullDirection[0] + kPullDirection[1] * kPullDirection[1] +
                             kPullDirection[2] * kPullDirection[2]);
  char radius[32];
  std::snprintf(radius, sizeof radius, "%g", kGrabRadiusMm);
  add(0, "\"type\": \"begin\", \"tool\": \"grab\", \"radius_mm\": " + std::string(radius) + ", \"position_mm\": " + vec_text(apex));
  const int moves = static_cast<int>(std::lround(kDragEnd / kTick));
  for (int k = 1; k <= moves; ++k) {
    const double s = kDragMm * k / moves;
    std::array<double, 3> p{};
    for (size_t c = 0; c < 3; ++c) p[c] = apex[c] + s * kPullDirection[c] / n;
    add(k * kTick, "\"type\": \"move\", \"id\": 0, \"position_mm\": " + vec_text(p));
  }
  add(kGrabEnd, "\"type\": \"end\", \"id\": 0");
  add(kGrabEnd, "\"type\": \"begin\", \"tool\": \"cut\", \"blade_edge_mm\": " + vec_text(kBladeEdge) + ", \"position_mm\": " +
                    vec_text(kCutFrom));
  const int cut_moves = static_cast<int>(std::lround((kCutEnd - kGrabEnd) / kTick));
  for (int k = 1; k <= cut_moves; ++k) {
    std::array<double, 3> p{};
    for (size_t c = 0; c < 3; ++c) p[c] = kCutFrom[c] + (kCutTo[c] - kCutFrom[c]) * k / cut_moves;
    add(kGrabEnd + k * kTick, "\"type\": \"move\", \"id\": 1, \"position_mm\": " + vec_text(p));
  }
  add(kCutEnd, "\"type\": \"end\", \"id\": 1");
  return script;
}

// Hands a parsed message to the session as the server does.
void apply(LiveSession& session, const LiveMessage& m) {
  switch (m.type) {
    case LiveMessage::Type::begin: {
      session.begin_tool(live_tool_spec(m));
      break;
    }
    case LiveMessage::Type::move: session.move_tool(m.id, m.position_mm); break;
    case LiveMessage::Type::end: session.end_tool(m.id); break;
    case LiveMessage::Type::pause: session.pause(); break;
    case LiveMessage::Type::resume: session.resume(); break;
    case LiveMessage::Type::reset: session.reset(); break;
    case LiveMessage::Type::save: break;
  }
}

// The scenario's text without `tools:` (a live session adds the user's), with the case's changes.
std::string live_text(const fs::path& file, const Case& c, int threads, const std::string& backend) {
  YAML::Node root = YAML::LoadFile(file.string());
  root.remove("tools");
  root.remove("render");
  if (!c.material_law.empty()) root["material"]["law"] = c.material_law;
  if (!c.nonlinear.empty()) root["solver"]["nonlinear"] = c.nonlinear;
  if (c.tolerance_mm > 0) root["solver"]["tolerance_mm"] = c.tolerance_mm;
  if (threads > 0) root["threads"] = threads;
  if (!backend.empty()) root["backend"] = backend;
  YAML::Emitter out;
  out << root;
  return out.c_str();
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(std::ceil(q * static_cast<double>(v.size())) - 1));
  return v[k];
}

struct Run {
  double setup_s = 0;      // the session's construction (files, model, factorisations)
  double wall_s = 0, sim_s = 0;
  double drag_sim_s = 0;   // simulated time advanced while dragging (kDragFrom .. kDragEnd of wall time)
  int64_t drag_pictures = 0;
  int64_t ticks = 0, steps = 0, halvings = 0;
  std::vector<double> tick_s;
  size_t vertices = 0, triangles = 0;
  size_t frame_bytes_max = 0, frames_with_triangles = 0;
  std::string stopped;     // the session's stop message, if it stopped
  std::string refused;     // a message the session refused (InputError)
  int64_t springs_cut = 0, triangles_cut = 0;  // the engine's metrics at the end
};

Run run(const Scenario& scenario, const std::string& text, bool paced) {
  Run r;
  const auto t0 = Clock::now();
  LiveSession session(scenario, text);
  session.set_move_ramp_s(kTick);  // as ctsurg-live: a move travels over a tick
  r.setup_s = std::chrono::duration<double>(Clock::now() - t0).count();
  LiveProtocolLimits limits;
  limits.bounds = session.rest_bounds();
  // The apex: the surface vertex nearest the point at fractions (0.75, 0, 0.2) of the rest box.
  std::vector<float> surface;
  session.surface(surface);
  r.vertices = surface.size() / 3;
  r.triangles = session.triangles().size() / 3;
  std::array<double, 3> target{}, apex{};
  const std::array<double, 3> fraction{0.75, 0, 0.2};
  for (size_t c = 0; c < 3; ++c) target[c] = limits.bounds[c] + fraction[c] * (limits.bounds[3 + c] - limits.bounds[c]);
  double best = 1e300;
  for (size_t i = 0; i < r.vertices; ++i) {
    double d = 0;
    for (size_t c = 0; c < 3; ++c) d += (surface[3 * i + c] - target[c]) * (surface[3 * i + c] - target[c]);
    if (d < best) {
      best = d;
      for (size_t c = 0; c < 3; ++c) apex[c] = surface[3 * i + c];
    }
  }
  const std::vector<Message> script = user_script(apex);
  if (g_verbose) {
    std::fprintf(stderr, "rest box %.1f %.1f %.1f .. %.1f %.1f %.1f, apex %.1f %.1f %.1f, dt %.3g s\n", limits.bounds[0], limits.bounds[1],
                 limits.bounds[2], limits.bounds[3], limits.bounds[4], limits.bounds[5], apex[0], apex[1], apex[2], session.dt());
  }

  size_t next = 0;
  uint64_t sent_topology = 0;
  const double sim0 = session.time();
  const int64_t steps0 = session.steps();
  const auto start = Clock::now();
  auto deadline = start;
  const auto since = [&](Clock::time_point t) { return std::chrono::duration<double>(t - start).count(); };
  LiveClock clock(kTick, 1.0);  // paced: as ctsurg-live's simulation thread
  for (;;) {
    const auto tick_start = Clock::now();
    const double now = since(tick_start);
    if (now >= kCutEnd + kTick && next == script.size()) break;
    while (next < script.size() && script[next].at_s <= now) {
      try {
        apply(session, parse_live_message(script[next].text, limits));
      } catch (const InputError& e) {
        if (r.refused.empty()) r.refused = e.what();
      }
      ++next;
    }
    double advanced = 0, advance_wall = 0;
    if (!paced) {
      advanced = session.advance(kTick).sim_s;
    } else if (clock.owed(session.paused())) {
      const LiveAdvance a = session.advance(clock.budget_s(), clock.advance_factor());
      clock.advanced(a.sim_s);
      advanced = a.sim_s;
      advance_wall = a.wall_s;
    }
    // The server sends a picture when something changed (a quasi-static model skips ticks).
    if (advanced == 0 && session.topology_version() == sent_topology) {
      if (paced) {
        clock.tick_done(std::chrono::duration<double>(Clock::now() - tick_start).count(), 0);
        deadline = std::max(deadline + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(kTick)), Clock::now());
        std::this_thread::sleep_until(deadline);
      }
      continue;
    }
    const bool dragging = now >= kDragFrom && now < kDragEnd;
    if (dragging) {
      r.drag_sim_s += advanced;
      ++r.drag_pictures;
    }
    const LiveFrame frame = live_frame_of(session, static_cast<uint64_t>(r.ticks), sent_topology);
    const std::vector<uint8_t> bytes = encode_live_frame(frame);
    sent_topology = frame.topology_version;
    r.frame_bytes_max = std::max(r.frame_bytes_max, bytes.size());
    if (frame.flags & LiveFrame::triangles_follow) ++r.frames_with_triangles;
    if (!session.stopped_message().empty() && r.stopped.empty()) r.stopped = session.stopped_message();
    r.triangles = std::max(r.triangles, size_t{frame.triangle_count});
    const double tick_s = std::chrono::duration<double>(Clock::now() - tick_start).count();
    if (g_verbose && (r.ticks % 10 == 0 || (frame.flags & LiveFrame::triangles_follow) || tick_s > 0.1)) {
      const EngineMetrics m = session.engine().metrics();
      std::fprintf(stderr, "tick %lld (%.3f s) wall %.3f sim %.4f steps %lld topology %llu F %u messages %zu springs cut %lld triangles cut %lld%s\n",
                   static_cast<long long>(r.ticks), tick_s, now, session.time(), static_cast<long long>(session.steps()),
                   static_cast<unsigned long long>(frame.topology_version), frame.triangle_count, next,
                   static_cast<long long>(m.springs_cut), static_cast<long long>(m.triangles_removed),
                   session.stopped_message().empty() ? "" : " stopped");
    }
    ++r.ticks;
    r.tick_s.push_back(tick_s);
    if (paced) {
      clock.tick_done(tick_s, advance_wall);
      deadline = std::max(deadline + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(kTick)), Clock::now());
      std::this_thread::sleep_until(deadline);
    }
  }
  r.wall_s = since(Clock::now());
  r.sim_s = session.time() - sim0;
  r.steps = session.steps() - steps0;
  r.halvings = session.halvings();
  const EngineMetrics m = session.engine().metrics();
  r.springs_cut = m.springs_cut;
  r.triangles_cut = m.triangles_removed;
  return r;
}

std::string fixed(double v, int digits) {
  char s[64];
  std::snprintf(s, sizeof s, "%.*f", digits, v);
  return s;
}

std::string thousands(size_t v) {
  const std::string digits = std::to_string(v);
  std::string s;
  for (size_t k = 0; k < digits.size(); ++k) {
    if (k > 0 && (digits.size() - k) % 3 == 0) s += ',';
    s += digits[k];
  }
  return s;
}

std::string short_message(std::string m) {
  for (char& ch : m) {
    if (ch == '|' || ch == '\n') ch = ' ';
  }
  return m.size() > 160 ? m.substr(0, 157) + "..." : m;
}

}  // namespace

int main(int argc, char** argv) {
  fs::path heart, scenarios = fs::path(CTSURG_SOURCE_DIR) / "data_samples" / "scenarios";
  std::string which = "grid,explicit,fem_static,fem_static_mm,fem_static_qn,fem_dynamic,fem_linear,fem_local,live";
  int threads = 0;
  std::string backend;
  bool markdown = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--heart" && i + 1 < argc) heart = argv[++i];
    else if (a == "--scenarios" && i + 1 < argc) scenarios = argv[++i];
    else if (a == "--cases" && i + 1 < argc) which = argv[++i];
    else if (a == "--threads" && i + 1 < argc) threads = std::atoi(argv[++i]);
    else if (a == "--backend" && i + 1 < argc) backend = argv[++i];
    else if (a == "--markdown") markdown = true;
    else if (a == "--verbose") g_verbose = true;
    else {
      std::cerr << "usage: bench_live_session --heart DIR [--scenarios DIR] [--cases grid,explicit,fem_static,fem_dynamic,"
                   "fem_static_mm,fem_static_qn,fem_linear,fem_local,live] [--threads N] [--backend cpu|cuda|auto] [--markdown] [--verbose]\n";
      return 2;
    }
  }
  for (const char* f : {"grid.h5", "surface_textured.h5", "tetmesh.h5"}) {
    if (heart.empty() || !fs::exists(heart / f)) {
      std::cerr << "bench_live_session: --heart DIR must hold the demo's grid.h5, surface_textured.h5 and tetmesh.h5 (missing "
                << (heart / f).string() << ")\n";
      return 2;
    }
  }
  if (markdown) {
    std::cout << "| model | threads | setup (s) | steps (per sim s) | real-time factor | pictures/s | while dragging: real-time factor, "
                 "pictures/s | picture median / p95 (ms) "
                 "| unpaced: pictures/s, real-time factor | bytes/frame: positions / with triangles | frames with "
                 "triangles | target while dragging (RTF >= 1, >= 30 pictures/s) | notes |\n"
              << "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|\n";
  }
  int status = 0;
  for (const Case& c : kCases) {
    if (("," + which + ",").find("," + c.name + ",") == std::string::npos) continue;
    if (!fs::exists(scenarios / c.scenario)) {
      std::cout << "| " << c.label << " | | | | | | | | | | | absent | no " << (scenarios / c.scenario).string() << " |" << std::endl;
      continue;
    }
    try {
      const std::string text = live_text(scenarios / c.scenario, c, threads, backend);
      const Scenario scenario = parse_scenario(text, heart / ("live_" + c.name + ".yaml"), heart);
      const Run paced = run(scenario, text, true);
      const Run unpaced = run(scenario, text, false);
      const double rtf = paced.sim_s / paced.wall_s, pictures = static_cast<double>(paced.ticks) / paced.wall_s;
      const double unpaced_pictures = static_cast<double>(unpaced.ticks) / unpaced.wall_s;
      const double drag_wall = kDragEnd - kDragFrom;
      const double drag_rtf = paced.drag_sim_s / drag_wall, drag_pictures = static_cast<double>(paced.drag_pictures) / drag_wall;
      const bool met = drag_rtf >= 0.95 && drag_pictures >= 30;  // 0.95: ticks at the window's edges
      std::string notes = "cut: " + thousands(static_cast<size_t>(paced.springs_cut)) + " springs (FEM: faces) separated, " +
                          thousands(static_cast<size_t>(paced.triangles_cut)) + " surface triangles removed; ";
      if (paced.halvings > 0) notes += std::to_string(paced.halvings) + " step halvings; ";
      if (!paced.stopped.empty()) notes += "stopped: " + short_message(paced.stopped) + "; ";
      if (!paced.refused.empty()) notes += "refused: " + short_message(paced.refused) + "; ";
      if (!notes.empty()) notes.resize(notes.size() - 2);
      const std::string thread_text = (threads > 0 ? std::to_string(threads) : "auto") + (backend == "cuda" ? ", CUDA" : "");
      std::cout << "| " << c.label << " | " << thread_text << " | " << fixed(paced.setup_s, 2) << " | " << thousands(static_cast<size_t>(paced.steps))
                << " (" << thousands(static_cast<size_t>(std::lround(paced.steps / std::max(paced.sim_s, 1e-12)))) << ") | "
                << fixed(rtf, 3) << " | " << fixed(pictures, 1) << " | " << fixed(drag_rtf, 3) << ", " << fixed(drag_pictures, 1)
                << " | " << fixed(1e3 * percentile(paced.tick_s, 0.5), 1) << " / "
                << fixed(1e3 * percentile(paced.tick_s, 0.95), 1) << " | " << fixed(unpaced_pictures, 1) << ", "
                << fixed(unpaced.sim_s / unpaced.wall_s, 3) << " | " << thousands(LiveFrame::kHeaderBytes + 12 * paced.vertices)
                << " / " << thousands(paced.frame_bytes_max) << " (V " << thousands(paced.vertices) << ", F "
                << thousands(paced.triangles) << ") | " << paced.frames_with_triangles << " of " << paced.ticks
                << " | " << (met ? "met" : "not met") << " | " << notes << " |" << std::endl;
    } catch (const InputError& e) {  // the scenario cannot be a live session
      std::cout << "| " << c.label << " | | | | | | | | | | | not live | " << short_message(e.what()) << " |" << std::endl;
    } catch (const std::exception& e) {
      std::cout << "| " << c.label << " | | | | | | | | | | failed | " << short_message(e.what()) << " |" << std::endl;
      status = 1;
    }
  }
  return status;
}
