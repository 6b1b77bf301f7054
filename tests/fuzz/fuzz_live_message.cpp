// libFuzzer target: what a browser sends ctsurg-live (live_protocol.h), which is hostile input. Each input
// goes through
//   1. parse_live_message, with the limits the server uses on the bundled heart (its rest box, a 50 mm
//      margin, 4 KiB, ids up to 2^20);
//   2. decode_live_frame on the same bytes, then on them with a valid magic and version written over the
//      start, then with the counts also made to fit the size (so that the triangle index checks are
//      reached, not only the magic).
// The only outcome allowed besides acceptance is ctsurg's refusal, InputError: any other exception
// escapes and libFuzzer reports it (as a crash, sanitizer report, hang or out-of-memory). An accepted
// message or frame must also keep the protocol's promises, checked here (a failed check aborts):
// positions finite and inside the box enlarged by the margin, radii in (0, 50] mm, blade edges in
// (0, 200] mm, ids in 0 .. max_id, and written back out as JSON it parses to the same
// message; a decoded frame has exactly the bytes its counts say, triangle indices below V, and encodes
// back to the same bytes (the header's padding aside).
#include "ctsurg/core/error.h"
#include "ctsurg/sim/live/live_protocol.h"
#include "ctsurg/sim/live/live_session.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string_view>
#include <vector>

namespace {

using namespace ctsurg;
using namespace ctsurg::sim;

[[noreturn]] void broken(const char* what) {
  std::fprintf(stderr, "fuzz_live_message: an accepted input breaks the protocol: %s\n", what);
  std::abort();
}
void check(bool ok, const char* what) {
  if (!ok) broken(what);
}

// The server's limits on the demo heart: its rest bounding box (LPS mm, build-dev/demo/heart's surface,
// rounded out), the default margin, size and id bounds.
LiveProtocolLimits heart_limits() {
  LiveProtocolLimits limits;
  limits.bounds = {-40, -300, 560, 100, -150, 700};
  return limits;
}

bool inside(const std::array<double, 3>& p, const LiveProtocolLimits& limits) {
  for (size_t c = 0; c < 3; ++c) {
    if (!std::isfinite(p[c]) || p[c] < limits.bounds[c] - limits.margin_mm || p[c] > limits.bounds[3 + c] + limits.margin_mm) {
      return false;
    }
  }
  return true;
}

// The message as a client would write it: parses back to the same message.
std::string json_of(const LiveMessage& m) {
  nlohmann::json j;
  const auto vec = [](const std::array<double, 3>& v) { return nlohmann::json::array({v[0], v[1], v[2]}); };
  switch (m.type) {
    case LiveMessage::Type::begin:
      j["type"] = "begin";
      j["tool"] = m.tool->name;
      if (m.tool->record == ToolRecord::blade) {
        j["blade_edge_mm"] = vec(m.blade_edge_mm);
      } else {
        j["radius_mm"] = m.radius_mm;
      }
      j["position_mm"] = vec(m.position_mm);
      break;
    case LiveMessage::Type::move:
      j["type"] = "move";
      j["id"] = m.id;
      j["position_mm"] = vec(m.position_mm);
      break;
    case LiveMessage::Type::end:
      j["type"] = "end";
      j["id"] = m.id;
      break;
    case LiveMessage::Type::pause: j["type"] = "pause"; break;
    case LiveMessage::Type::resume: j["type"] = "resume"; break;
    case LiveMessage::Type::reset: j["type"] = "reset"; break;
    case LiveMessage::Type::save: j["type"] = "save"; break;
  }
  if (m.has_seq) j["seq"] = m.seq;
  return j.dump();
}

bool same(const LiveMessage& a, const LiveMessage& b) {
  return a.type == b.type && a.tool == b.tool && a.radius_mm == b.radius_mm && a.blade_edge_mm == b.blade_edge_mm &&
         a.position_mm == b.position_mm && a.id == b.id && a.has_seq == b.has_seq && a.seq == b.seq;
}

void check_message(std::string_view text, const LiveMessage& m, const LiveProtocolLimits& limits) {
  check(text.size() <= limits.max_bytes, "a message over max_bytes was accepted");
  using T = LiveMessage::Type;
  if (m.type == T::begin) {
    check(inside(m.position_mm, limits), "begin: position outside the box + margin, or not finite");
    check(m.tool != nullptr && m.tool->live, "begin: no tool, or one the page cannot begin");
    if (m.tool->record == ToolRecord::blade) {
      const auto& e = m.blade_edge_mm;
      const double l = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
      check(std::isfinite(l) && l > 0 && l <= kMaxLiveBladeMm, "begin cut: blade edge length outside (0, 200] mm");
    } else {
      check(m.tool->live && m.tool->record == ToolRecord::sphere, "begin: a tool the page cannot begin");
      check(m.radius_mm > 0 && m.radius_mm <= kMaxLiveToolRadiusMm, "begin: radius outside (0, 50] mm");
    }
  } else if (m.type == T::move) {
    check(m.id >= 0 && m.id <= limits.max_id, "move: id out of range");
    check(inside(m.position_mm, limits), "move: position outside the box + margin, or not finite");
  } else if (m.type == T::end) {
    check(m.id >= 0 && m.id <= limits.max_id, "end: id out of range");
  } else {
    check(m.type == T::pause || m.type == T::resume || m.type == T::reset || m.type == T::save, "an unknown type");
  }
  const std::string again = json_of(m);
  LiveMessage back;
  try {
    back = parse_live_message(again, limits);
  } catch (const InputError&) {
    broken("an accepted message, written back as JSON, is refused");
  }
  check(same(m, back), "an accepted message, written back as JSON, parses to another message");
}

void check_frame(std::span<const uint8_t> bytes, const LiveFrame& f) {
  const size_t nv = f.positions.size() / 3;
  check(f.positions.size() % 3 == 0, "frame: positions not a multiple of 3");
  const bool tris = (f.flags & LiveFrame::triangles_follow) != 0;
  check(tris ? f.triangles.size() == 3 * size_t{f.triangle_count} : f.triangles.empty(), "frame: triangles do not match F");
  check(bytes.size() == LiveFrame::kHeaderBytes + 12 * nv + 4 * f.triangles.size(), "frame: size does not match the counts");
  for (const uint32_t v : f.triangles) check(v < nv, "frame: a triangle index beyond V");
  std::vector<uint8_t> again = encode_live_frame(f);
  std::vector<uint8_t> original(bytes.begin(), bytes.end());
  std::memset(original.data() + 52, 0, 4);  // the padding is written as 0 and not read
  check(again == original, "frame: encoding the decoded frame gives other bytes");
}

void decode(std::span<const uint8_t> bytes) {
  try {
    check_frame(bytes, decode_live_frame(bytes));
  } catch (const InputError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const LiveProtocolLimits limits = heart_limits();
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    check_message(text, parse_live_message(text, limits), limits);
  } catch (const InputError&) {
  }

  decode({data, size});
  if (size < LiveFrame::kHeaderBytes) return 0;
  std::vector<uint8_t> bytes(data, data + size);
  std::memcpy(bytes.data(), "CTLF", 4);
  const uint16_t version = LiveFrame::kVersion;
  std::memcpy(bytes.data() + 4, &version, 2);
  decode(bytes);
  // The counts made to fit: V from the size (with the triangles, F takes what is left after V's share).
  const size_t data_bytes = size - LiveFrame::kHeaderBytes;
  uint16_t flags;
  std::memcpy(&flags, bytes.data() + 6, 2);
  uint32_t nv = 0, nf = 0;
  if (flags & LiveFrame::triangles_follow) {
    std::memcpy(&nv, bytes.data() + 40, 4);
    nv %= data_bytes / 12 + 1;
    nf = static_cast<uint32_t>((data_bytes - 12 * size_t{nv}) / 12);
  } else {
    nv = static_cast<uint32_t>(data_bytes / 12);
    std::memcpy(&nf, bytes.data() + 44, 4);
  }
  std::memcpy(bytes.data() + 40, &nv, 4);
  std::memcpy(bytes.data() + 44, &nf, 4);
  decode(bytes);
  return 0;
}
