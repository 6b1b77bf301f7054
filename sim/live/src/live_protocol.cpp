#include "ctsurg/sim/live/live_protocol.h"

#include "ctsurg/core/error.h"

#include <nlohmann/json.hpp>

#include <bit>
#include <cmath>
#include <cstring>
#include <set>
#include <string>
#include <variant>

namespace ctsurg::sim {

static_assert(std::endian::native == std::endian::little, "the live frame is written as the host's little-endian bytes");

namespace {

using nlohmann::json;

[[noreturn]] void refuse(const std::string& field, const std::string& problem) { throw InputError("message", field, problem); }

std::string number_text(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

const json& member(const json& m, const char* key) {
  const auto it = m.find(key);
  if (it == m.end()) refuse(key, "missing");
  return *it;
}

double finite_number(const json& v, const std::string& field) {
  if (!v.is_number()) refuse(field, "must be a number");
  const double x = v.get<double>();
  if (!std::isfinite(x)) refuse(field, "must be finite");
  return x;
}

std::array<double, 3> vec3(const json& v, const std::string& field) {
  if (!v.is_array() || v.size() != 3) refuse(field, "must be [x, y, z]");
  std::array<double, 3> out{};
  for (size_t c = 0; c < 3; ++c) out[c] = finite_number(v[c], field + "[" + std::to_string(c) + "]");
  return out;
}

std::array<double, 3> position(const json& m, const LiveProtocolLimits& limits) {
  const std::array<double, 3> p = vec3(member(m, "position_mm"), "position_mm");
  for (size_t c = 0; c < 3; ++c) {
    const double lo = limits.bounds[c] - limits.margin_mm, hi = limits.bounds[3 + c] + limits.margin_mm;
    if (p[c] < lo || p[c] > hi) {
      refuse("position_mm[" + std::to_string(c) + "]", number_text(p[c]) + " mm is outside the model's box enlarged by " +
                                                           number_text(limits.margin_mm) + " mm (" + number_text(lo) + " .. " +
                                                           number_text(hi) + ")");
    }
  }
  return p;
}

int tool_id(const json& m, const LiveProtocolLimits& limits) {
  const json& v = member(m, "id");
  if (!v.is_number_integer()) refuse("id", "must be an integer");
  const int64_t id = v.is_number_unsigned() && v.get<uint64_t>() > static_cast<uint64_t>(INT64_MAX) ? -1 : v.get<int64_t>();
  if (id < 0 || id > limits.max_id) refuse("id", "must be in 0 .. " + std::to_string(limits.max_id));
  return static_cast<int>(id);
}

void only(const json& m, std::set<std::string> keys) {
  keys.insert("seq");  // any message may carry it
  for (const auto& [key, value] : m.items()) {
    if (!keys.count(key)) refuse(key.size() > 40 ? key.substr(0, 40) + "..." : key, "unknown key for this type");
  }
}

template <typename T>
void put_le(std::vector<uint8_t>& out, size_t at, T value) {
  std::memcpy(out.data() + at, &value, sizeof value);
}

template <typename T>
T get(std::span<const uint8_t> in, size_t at) {
  T value;
  std::memcpy(&value, in.data() + at, sizeof value);
  return value;
}

}  // namespace

LiveMessage parse_live_message(std::string_view text, const LiveProtocolLimits& limits) {
  if (text.size() > limits.max_bytes) {
    refuse("(text)", std::to_string(text.size()) + " bytes: a message is at most " + std::to_string(limits.max_bytes));
  }
  const json m = json::parse(text.begin(), text.end(), nullptr, false);
  if (m.is_discarded()) refuse("(text)", "not JSON");
  if (!m.is_object()) refuse("(text)", "must be a JSON object");
  const json& type = member(m, "type");
  if (!type.is_string()) refuse("type", "must be a string");
  const std::string t = type.get<std::string>();
  LiveMessage out;
  if (const auto seq = m.find("seq"); seq != m.end()) {
    if (!seq->is_number_integer()) refuse("seq", "must be an integer");
    if (!seq->is_number_unsigned() && seq->get<int64_t>() < 0) refuse("seq", "must be in 0 .. 4294967295");
    if (seq->get<uint64_t>() > UINT32_MAX) refuse("seq", "must be in 0 .. 4294967295");
    out.has_seq = true;
    out.seq = static_cast<uint32_t>(seq->get<uint64_t>());
  }
  if (t == "begin") {
    out.type = LiveMessage::Type::begin;
    const json& tool = member(m, "tool");
    if (!tool.is_string()) refuse("tool", "must be a string");
    const std::string kind = tool.get<std::string>();
    const ToolType* begun = find_tool_type(kind);
    if (begun == nullptr || !begun->live) refuse("tool", "must be one of the live tools: " + live_tool_names());
    out.tool = begun;
    if (begun->record == ToolRecord::sphere) {
      only(m, {"type", "tool", "radius_mm", "position_mm"});
      out.radius_mm = finite_number(member(m, "radius_mm"), "radius_mm");
      if (!(out.radius_mm > 0) || out.radius_mm > kMaxLiveToolRadiusMm) {
        refuse("radius_mm", number_text(out.radius_mm) + " is outside (0, " + number_text(kMaxLiveToolRadiusMm) + "] mm");
      }
    } else if (begun->record == ToolRecord::blade) {
      only(m, {"type", "tool", "blade_edge_mm", "position_mm"});
      out.blade_edge_mm = vec3(member(m, "blade_edge_mm"), "blade_edge_mm");
      const auto& e = out.blade_edge_mm;
      const double l = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
      if (!(l > 0) || l > kMaxLiveBladeMm) {
        refuse("blade_edge_mm", "its length " + number_text(l) + " mm is outside (0, " + number_text(kMaxLiveBladeMm) + "] mm");
      }
    } else {
      refuse("tool", std::string(begun->name) + " has no live form (a sphere or a blade)");
    }
    out.position_mm = position(m, limits);
  } else if (t == "move") {
    only(m, {"type", "id", "position_mm"});
    out.type = LiveMessage::Type::move;
    out.id = tool_id(m, limits);
    out.position_mm = position(m, limits);
  } else if (t == "end") {
    only(m, {"type", "id"});
    out.type = LiveMessage::Type::end;
    out.id = tool_id(m, limits);
  } else if (t == "pause" || t == "resume" || t == "reset" || t == "save") {
    only(m, {"type"});
    out.type = t == "pause" ? LiveMessage::Type::pause : t == "resume" ? LiveMessage::Type::resume
             : t == "reset" ? LiveMessage::Type::reset : LiveMessage::Type::save;
  } else {
    refuse("type", "must be begin, move, end, pause, resume, reset or save");
  }
  return out;
}

namespace {

// One JSON object per server message; nlohmann::json keeps its keys sorted, so the text does not
// depend on the order they are listed in.
json server_message_json(const LiveHello& m) {
  json h{{"type", "hello"},
         {"scenario", m.scenario},
         {"model", m.model},
         {"vertex_count", m.vertex_count},
         {"triangle_count", m.triangle_count},
         {"bounds", m.bounds},
         {"margin_mm", m.margin_mm},
         {"dt_s", m.dt_s},
         {"colour", m.colour},
         {"uvs", m.uvs},
         {"normal_map", nullptr},
         {"tools", {{"grab_radius_mm", m.grab_radius_mm}, {"probe_radius_mm", m.probe_radius_mm}, {"cut_depth_mm", m.cut_depth_mm}}},
         {"save_to", nullptr},
         {"library", m.library},
         {"version", m.version}};
  if (m.normal_map) h["normal_map"] = {{"width", (*m.normal_map)[0]}, {"height", (*m.normal_map)[1]}};
  if (m.save_to) h["save_to"] = {{"scenario", (*m.save_to)[0]}, {"trajectory", (*m.save_to)[1]}};
  return h;
}

json server_message_json(const LiveBegan& m) {
  json b{{"type", "began"}, {"id", m.id}};
  if (m.seq) b["seq"] = *m.seq;
  return b;
}

json server_message_json(const LiveEnded& m) { return {{"type", "ended"}, {"id", m.id}, {"why", m.why}}; }

json server_message_json(const LiveStatus& m) {
  json loads = json::array();
  for (const LiveToolLoad& l : m.loads) loads.push_back({{"id", l.id}, {"force_n", l.force_n}, {"moment_n_mm", l.moment_n_mm}});
  return {{"type", "status"},
          {"loads", loads},
          {"solver_error_mm", std::isfinite(m.solver_error_mm) ? json(m.solver_error_mm) : json(nullptr)},
          {"time_s", m.time_s},
          {"steps", m.steps},
          {"dt_s", m.dt_s},
          {"rtf", m.rtf},
          {"pictures_per_s", m.pictures_per_s},
          {"paused", m.paused},
          {"stopped", m.stopped},
          {"halvings", m.halvings},
          {"frames_recorded", m.frames_recorded},
          {"frame_bytes", m.frame_bytes}};
}

json server_message_json(const LiveGuard& m) {
  const char* action = "halved";
  switch (m.action) {
    case LiveGuard::Action::halved: action = "halved"; break;
    case LiveGuard::Action::stopped: action = "stopped"; break;
  }
  return {{"type", "guard"}, {"action", action}, {"message", m.message}};
}

json server_message_json(const LiveError& m) {
  json e{{"type", "error"}, {"message", m.message}};
  if (m.seq) e["seq"] = *m.seq;
  return e;
}

json server_message_json(const LiveSaved& m) {
  json s{{"type", "saved"}, {"scenario", m.scenario}, {"trajectory", m.trajectory}, {"frames", m.frames}, {"time_s", m.time_s}};
  if (m.seq) s["seq"] = *m.seq;
  return s;
}

json server_message_json(const LiveClosed& m) { return {{"type", "closed"}, {"message", m.message}}; }

}  // namespace

std::string encode_live_server_message(const LiveServerMessage& message) {
  return std::visit([](const auto& m) { return server_message_json(m).dump(); }, message);
}

std::vector<uint8_t> encode_live_frame(const LiveFrame& f) {
  const bool tris = (f.flags & LiveFrame::triangles_follow) != 0;
  if (f.positions.size() % 3 != 0 || (tris && f.triangles.size() != 3 * static_cast<size_t>(f.triangle_count))) {
    throw RuntimeError("live frame: " + std::to_string(f.positions.size()) + " coordinates, " +
                       std::to_string(f.triangles.size()) + " triangle indices for " + std::to_string(f.triangle_count) +
                       " triangles");
  }
  const size_t nv = f.positions.size() / 3;
  std::vector<uint8_t> out(LiveFrame::kHeaderBytes + 4 * f.positions.size() + (tris ? 4 * f.triangles.size() : 0));
  std::memcpy(out.data(), "CTLF", 4);
  put_le<uint16_t>(out, 4, LiveFrame::kVersion);
  put_le<uint16_t>(out, 6, f.flags);
  put_le<uint64_t>(out, 8, f.frame);
  put_le<double>(out, 16, f.time_s);
  put_le<int64_t>(out, 24, f.steps);
  put_le<uint64_t>(out, 32, f.topology_version);
  put_le<uint32_t>(out, 40, static_cast<uint32_t>(nv));
  put_le<uint32_t>(out, 44, f.triangle_count);
  put_le<uint32_t>(out, 48, f.seq);
  put_le<uint32_t>(out, 52, 0);
  // An empty vector's data() may be null, and memcpy from null is undefined even for 0 bytes (a fuzz
  // finding: tests/fuzz_regressions/README.md): no copy without data.
  if (!f.positions.empty()) std::memcpy(out.data() + LiveFrame::kHeaderBytes, f.positions.data(), 4 * f.positions.size());
  if (tris && !f.triangles.empty()) std::memcpy(out.data() + LiveFrame::kHeaderBytes + 4 * f.positions.size(), f.triangles.data(), 4 * f.triangles.size());
  return out;
}

LiveFrame decode_live_frame(std::span<const uint8_t> in) {
  if (in.size() < LiveFrame::kHeaderBytes) throw InputError("frame", "header", std::to_string(in.size()) + " bytes, shorter than the header");
  if (std::memcmp(in.data(), "CTLF", 4) != 0) throw InputError("frame", "magic", "not CTLF");
  LiveFrame f;
  if (get<uint16_t>(in, 4) != LiveFrame::kVersion) throw InputError("frame", "version", std::to_string(get<uint16_t>(in, 4)) + ", expected " + std::to_string(LiveFrame::kVersion));
  f.flags = get<uint16_t>(in, 6);
  f.frame = get<uint64_t>(in, 8);
  f.time_s = get<double>(in, 16);
  f.steps = get<int64_t>(in, 24);
  f.topology_version = get<uint64_t>(in, 32);
  const uint64_t nv = get<uint32_t>(in, 40);
  f.triangle_count = get<uint32_t>(in, 44);
  f.seq = get<uint32_t>(in, 48);
  const bool tris = (f.flags & LiveFrame::triangles_follow) != 0;
  const uint64_t expected = LiveFrame::kHeaderBytes + 12 * nv + (tris ? 12 * uint64_t{f.triangle_count} : 0);
  if (in.size() != expected) {
    throw InputError("frame", "size", std::to_string(in.size()) + " bytes, the counts say " + std::to_string(expected));
  }
  f.positions.resize(3 * nv);
  if (nv > 0) std::memcpy(f.positions.data(), in.data() + LiveFrame::kHeaderBytes, 12 * nv);  // not to null (V = 0)
  if (tris && f.triangle_count > 0) {
    f.triangles.resize(3 * size_t{f.triangle_count});
    std::memcpy(f.triangles.data(), in.data() + LiveFrame::kHeaderBytes + 12 * nv, f.triangles.size() * 4);
    for (size_t k = 0; k < f.triangles.size(); ++k) {
      if (f.triangles[k] >= nv) throw InputError("frame", "triangles[" + std::to_string(k / 3) + "]", "vertex index beyond V");
    }
  }
  return f;
}

}  // namespace ctsurg::sim
