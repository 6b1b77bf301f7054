// Tests for ctsurg/sim/live/live_protocol.h: every client message parsed; malformed, oversized and
// out-of-range messages refused with the field named; random and mutated bytes only ever parsed or
// refused (an InputError, never another exception); every server text message encoded to its exact
// JSON text, with its numbers read back bit for bit; binary frames round-trip bit for bit, with and
// without triangles, and damaged frames are refused.
#include "ctsurg/sim/live/live_protocol.h"

#include "ctsurg/core/error.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <span>
#include <random>
#include <string>

using namespace ctsurg;
using namespace ctsurg::sim;

namespace {

LiveProtocolLimits bar_limits() {
  LiveProtocolLimits l;
  l.bounds = {11, -19, 31, 43, -11, 39};
  l.margin_mm = 20;
  return l;
}

// The refusal's message, or "" when it was accepted.
std::string refusal(const std::string& text) {
  try {
    parse_live_message(text, bar_limits());
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(LiveProtocol, ParsesEveryMessage) {
  const LiveProtocolLimits l = bar_limits();
  LiveMessage m = parse_live_message(R"({"type": "begin", "tool": "grab", "radius_mm": 2.5, "position_mm": [42, -15, 35]})", l);
  EXPECT_EQ(m.type, LiveMessage::Type::begin);
  EXPECT_STREQ(m.tool->name, "grab");
  EXPECT_EQ(m.radius_mm, 2.5);
  EXPECT_EQ(m.position_mm, (std::array<double, 3>{42, -15, 35}));
  m = parse_live_message(R"({"type":"begin","tool":"probe","radius_mm":3,"position_mm":[30,-15,41.25]})", l);
  EXPECT_STREQ(m.tool->name, "probe");
  m = parse_live_message(R"({"type":"begin","tool":"cut","blade_edge_mm":[0,0,20],"position_mm":[27,-25,35]})", l);
  EXPECT_STREQ(m.tool->name, "cut");
  EXPECT_EQ(m.blade_edge_mm, (std::array<double, 3>{0, 0, 20}));
  m = parse_live_message(R"({"type":"move","id":3,"position_mm":[27.125,-25,35]})", l);
  EXPECT_EQ(m.type, LiveMessage::Type::move);
  EXPECT_EQ(m.id, 3);
  EXPECT_EQ(m.position_mm[0], 27.125);
  m = parse_live_message(R"({"type":"end","id":0})", l);
  EXPECT_EQ(m.type, LiveMessage::Type::end);
  EXPECT_EQ(m.id, 0);
  EXPECT_EQ(parse_live_message(R"({"type":"pause"})", l).type, LiveMessage::Type::pause);
  EXPECT_EQ(parse_live_message(R"({"type":"resume"})", l).type, LiveMessage::Type::resume);
  EXPECT_EQ(parse_live_message(R"({"type":"reset"})", l).type, LiveMessage::Type::reset);
  EXPECT_EQ(parse_live_message(R"({"type":"save"})", l).type, LiveMessage::Type::save);
}

TEST(LiveProtocol, RefusesBadMessagesNamingTheField) {
  const auto expect_refused = [](const std::string& text, const std::string& field, const std::string& problem) {
    const std::string why = refusal(text);
    EXPECT_NE(why.find(field), std::string::npos) << text << " -> " << why;
    EXPECT_NE(why.find(problem), std::string::npos) << text << " -> " << why;
  };
  expect_refused("not json", "(text)", "not JSON");
  expect_refused("[1, 2]", "(text)", "object");
  expect_refused(std::string(2040, '[') + std::string(2040, ']'), "(text)", "object");  // as deep as 4 KiB allows
  expect_refused(R"({"type": "pause"} {"type": "reset"})", "(text)", "not JSON");
  expect_refused(R"({"type": "begin", "tool": "grab", "radius_mm": 2, "position_mm": [1, 2, 3], "pad": ")" +
                     std::string(5000, 'x') + "\"}",
                 "(text)", "at most 4096");
  expect_refused(R"({"tool": "grab"})", "type", "missing");
  expect_refused(R"({"type": 3})", "type", "string");
  expect_refused(R"({"type": "explode"})", "type", "must be");
  expect_refused(R"({"type": "begin", "tool": "force", "radius_mm": 2, "position_mm": [30, -15, 35]})", "tool", "one of the live tools: grab, probe, cut");
  expect_refused(R"({"type": "begin", "tool": "grab", "position_mm": [30, -15, 35]})", "radius_mm", "missing");
  expect_refused(R"({"type": "begin", "tool": "grab", "radius_mm": "2", "position_mm": [30, -15, 35]})", "radius_mm", "number");
  expect_refused(R"({"type": "begin", "tool": "grab", "radius_mm": -1, "position_mm": [30, -15, 35]})", "radius_mm", "outside");
  expect_refused(R"({"type": "begin", "tool": "probe", "radius_mm": 60, "position_mm": [30, -15, 35]})", "radius_mm", "outside");
  expect_refused(R"({"type": "begin", "tool": "cut", "blade_edge_mm": [0, 0, 0], "position_mm": [30, -15, 35]})", "blade_edge_mm", "outside");
  expect_refused(R"({"type": "begin", "tool": "cut", "blade_edge_mm": [0, 0, 300], "position_mm": [30, -15, 35]})", "blade_edge_mm", "outside");
  expect_refused(R"({"type": "begin", "tool": "cut", "blade_edge_mm": [0, 0], "position_mm": [30, -15, 35]})", "blade_edge_mm", "[x, y, z]");
  expect_refused(R"({"type": "move", "id": 0, "position_mm": [30, -15]})", "position_mm", "[x, y, z]");
  expect_refused(R"({"type": "move", "id": 0, "position_mm": [30, null, 35]})", "position_mm[1]", "number");
  expect_refused(R"({"type": "move", "id": 0, "position_mm": [30, -15, 1000]})", "position_mm[2]", "outside the model's box");
  expect_refused(R"({"type": "move", "id": 0, "position_mm": [-1e300, -15, 35]})", "position_mm[0]", "outside");
  expect_refused(R"({"type": "move", "id": -1, "position_mm": [30, -15, 35]})", "id", "0 ..");
  expect_refused(R"({"type": "move", "id": 1.5, "position_mm": [30, -15, 35]})", "id", "integer");
  expect_refused(R"({"type": "move", "id": 99999999999999999999, "position_mm": [30, -15, 35]})", "id", "");
  expect_refused(R"({"type": "end"})", "id", "missing");
  expect_refused(R"({"type": "pause", "now": true})", "now", "unknown key");
  expect_refused(R"({"type": "end", "id": 0, "position_mm": [30, -15, 35]})", "position_mm", "unknown key");
  // A number beyond double's range is refused, whether as JSON or as a number.
  EXPECT_NE(refusal(R"({"type": "move", "id": 0, "position_mm": [1e999, -15, 35]})"), "");
}

TEST(LiveProtocol, RandomAndMutatedBytesAreParsedOrRefusedNeverCrash) {
  std::mt19937 rng(22);
  const std::string valid[] = {R"({"type":"begin","tool":"cut","blade_edge_mm":[0,0,20],"position_mm":[27,-25,35]})",
                               R"({"type":"move","id":3,"position_mm":[27.125,-25,35]})", R"({"type":"end","id":0})"};
  int accepted = 0, refused = 0;
  for (int n = 0; n < 20000; ++n) {
    std::string text = valid[n % 3];
    if (n % 4 == 0) {
      text.assign(static_cast<size_t>(rng() % 200), '\0');
      for (char& c : text) c = static_cast<char>(rng() % 256);
    } else {
      const int edits = 1 + static_cast<int>(rng() % 4);
      for (int e = 0; e < edits; ++e) {
        const size_t at = rng() % text.size();
        switch (rng() % 3) {
          case 0: text[at] = static_cast<char>(rng() % 256); break;
          case 1: text.erase(text.begin() + static_cast<std::ptrdiff_t>(at)); break;
          default: text.insert(text.begin() + static_cast<std::ptrdiff_t>(at), "{}[]\",:0-e9."[rng() % 12]); break;
        }
        if (text.empty()) text.push_back('{');
      }
    }
    try {
      const LiveMessage m = parse_live_message(text, bar_limits());
      if (m.type == LiveMessage::Type::begin || m.type == LiveMessage::Type::move) {
        for (const double c : m.position_mm) ASSERT_TRUE(std::isfinite(c));
      }
      ++accepted;
    } catch (const InputError&) {
      ++refused;
    }
  }
  EXPECT_GT(accepted, 100);
  EXPECT_GT(refused, 10000);
}

TEST(LiveProtocol, AnyMessageMayCarryASequenceNumber) {
  const LiveMessage m = parse_live_message(R"({"type": "move", "id": 2, "position_mm": [30, -15, 35], "seq": 4294967295})", bar_limits());
  EXPECT_TRUE(m.has_seq);
  EXPECT_EQ(m.seq, 4294967295u);
  EXPECT_FALSE(parse_live_message(R"({"type": "pause"})", bar_limits()).has_seq);
  EXPECT_EQ(parse_live_message(R"({"type": "save", "seq": 0})", bar_limits()).seq, 0u);
  for (const char* bad : {R"({"type": "pause", "seq": -1})", R"({"type": "pause", "seq": 4294967296})",
                          R"({"type": "pause", "seq": 1.5})", R"({"type": "pause", "seq": "7"})",
                          R"({"type": "pause", "seq": 18446744073709551615})"}) {
    try {
      parse_live_message(bad, bar_limits());
      ADD_FAILURE() << bad << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("seq"), std::string::npos) << e.what();
    }
  }
}

TEST(LiveProtocol, FramesRoundTripBitForBit) {
  LiveFrame f;
  f.flags = LiveFrame::triangles_follow | LiveFrame::paused;
  f.frame = 123456789012345ull;
  f.time_s = 0.1 + 0.2;
  f.steps = 98765;
  f.topology_version = 7;
  f.seq = 4000000000u;
  f.positions = {1.5f, -2.25f, 600.125f, 0.1f, 1e-30f, -3e38f, 7, 8, 9};
  f.triangles = {0, 1, 2};
  f.triangle_count = 1;
  const std::vector<uint8_t> bytes = encode_live_frame(f);
  ASSERT_EQ(bytes.size(), LiveFrame::kHeaderBytes + 9 * 4 + 3 * 4);
  EXPECT_EQ(0, std::memcmp(bytes.data(), "CTLF", 4));
  const LiveFrame g = decode_live_frame(bytes);
  EXPECT_EQ(g.flags, f.flags);
  EXPECT_EQ(g.frame, f.frame);
  EXPECT_EQ(g.time_s, f.time_s);
  EXPECT_EQ(g.steps, f.steps);
  EXPECT_EQ(g.topology_version, f.topology_version);
  EXPECT_EQ(g.triangle_count, 1u);
  EXPECT_EQ(g.seq, f.seq);
  EXPECT_EQ(0, std::memcmp(g.positions.data(), f.positions.data(), 36));
  EXPECT_EQ(g.triangles, f.triangles);
  // Without the triangles: the count stays, the indices are not sent.
  f.flags = 0;
  f.triangles.clear();
  const std::vector<uint8_t> light = encode_live_frame(f);
  EXPECT_EQ(light.size(), LiveFrame::kHeaderBytes + 36);
  const LiveFrame h = decode_live_frame(light);
  EXPECT_EQ(h.triangle_count, 1u);
  EXPECT_TRUE(h.triangles.empty());
  // Damaged frames are refused, naming what is wrong.
  std::vector<uint8_t> bad = bytes;
  bad[0] = 'X';
  EXPECT_THROW(decode_live_frame(bad), InputError);
  bad = bytes;
  bad[4] = 1;  // version 1 had no seq (a 48-byte header)
  EXPECT_THROW(decode_live_frame(bad), InputError);
  bad = bytes;
  bad.pop_back();
  EXPECT_THROW(decode_live_frame(bad), InputError);
  bad = bytes;
  bad[bad.size() - 4] = 3;  // triangle index 3 >= V
  EXPECT_THROW(decode_live_frame(bad), InputError);
  EXPECT_THROW(decode_live_frame(std::span<const uint8_t>(bytes.data(), 10)), InputError);
}

// A fuzz finding (tests/fuzz_regressions/README.md): a frame without vertices made decode_live_frame
// memcpy to null.
TEST(LiveProtocol, AFrameWithoutVerticesDecodesAndEncodesBack) {
  const std::string bytes = ctsurg::test::read_bytes(ctsurg::test::source_dir() / "tests" / "fuzz_regressions" /
                                                     "fuzz_live_message" / "crash-c65ce571");
  const std::span<const uint8_t> in(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
  const LiveFrame f = decode_live_frame(in);
  EXPECT_TRUE(f.positions.empty());
  EXPECT_TRUE(f.triangles.empty());
  std::vector<uint8_t> expected(in.begin(), in.end());
  std::fill(expected.begin() + 52, expected.end(), 0);  // the padding
  EXPECT_EQ(encode_live_frame(f), expected);
  LiveFrame empty;
  empty.flags = LiveFrame::triangles_follow;
  EXPECT_EQ(decode_live_frame(encode_live_frame(empty)).triangle_count, 0u);
}

// The text of each server message, exactly: keys in alphabetical order, integers as integers, doubles
// as doubles, "seq" only when given. (The same text ctsurg-live assembled before its messages were
// typed: a scripted session's messages were compared byte for byte before and after.)
TEST(LiveProtocol, ServerMessagesEncodeToTheirExactText) {
  LiveHello h;
  h.scenario = "live bar";
  h.model = "spring_grid, 3 surface vertices";
  h.vertex_count = 3;
  h.triangle_count = 1;
  h.bounds = {11, -19, 31, 43, -11, 39};
  h.margin_mm = 20;
  h.dt_s = 0.001;
  h.colour = {0.5, 0.25, 0.125};
  h.grab_radius_mm = 8;
  h.probe_radius_mm = 6;
  h.cut_depth_mm = 15;
  h.library = "three 0.187.0";
  h.version = "ctsurg 0.1.0";
  EXPECT_EQ(encode_live_server_message(h),
            R"({"bounds":[11.0,-19.0,31.0,43.0,-11.0,39.0],"colour":[0.5,0.25,0.125],"dt_s":0.001,)"
            R"("library":"three 0.187.0","margin_mm":20.0,"model":"spring_grid, 3 surface vertices","normal_map":null,)"
            R"("save_to":null,"scenario":"live bar","tools":{"cut_depth_mm":15.0,"grab_radius_mm":8.0,"probe_radius_mm":6.0},)"
            R"("triangle_count":1,"type":"hello","uvs":false,"version":"ctsurg 0.1.0","vertex_count":3})");
  h.uvs = true;
  h.normal_map = std::array<int, 2>{256, 128};
  h.save_to = std::array<std::string, 2>{"/tmp/s \"1\".yaml", "/tmp/s.h5"};
  EXPECT_EQ(encode_live_server_message(h),
            R"({"bounds":[11.0,-19.0,31.0,43.0,-11.0,39.0],"colour":[0.5,0.25,0.125],"dt_s":0.001,)"
            R"("library":"three 0.187.0","margin_mm":20.0,"model":"spring_grid, 3 surface vertices",)"
            R"("normal_map":{"height":128,"width":256},"save_to":{"scenario":"/tmp/s \"1\".yaml","trajectory":"/tmp/s.h5"},)"
            R"("scenario":"live bar","tools":{"cut_depth_mm":15.0,"grab_radius_mm":8.0,"probe_radius_mm":6.0},)"
            R"("triangle_count":1,"type":"hello","uvs":true,"version":"ctsurg 0.1.0","vertex_count":3})");
  EXPECT_EQ(encode_live_server_message(LiveBegan{0, 5}), R"({"id":0,"seq":5,"type":"began"})");
  EXPECT_EQ(encode_live_server_message(LiveBegan{3, std::nullopt}), R"({"id":3,"type":"began"})");
  EXPECT_EQ(encode_live_server_message(LiveEnded{2, "the session was reset"}),
            R"({"id":2,"type":"ended","why":"the session was reset"})");
  EXPECT_EQ(encode_live_server_message(LiveStatus{0.25, 250, 0.001, 0.5, 59.5, true, "", 1, 26, 1592, {}}),
            R"({"dt_s":0.001,"frame_bytes":1592,"frames_recorded":26,"halvings":1,"loads":[],"paused":true,"pictures_per_s":59.5,)"
            R"("rtf":0.5,"solver_error_mm":null,"steps":250,"stopped":"","time_s":0.25,"type":"status"})");
  EXPECT_EQ(encode_live_server_message(LiveStatus{0, 0, 0, 0, 0, false, "", 0, 0, 0, {LiveToolLoad{1, {0.5, -0.25, 0}, {2, 0, -1}}}, 0.0375}),
            R"({"dt_s":0.0,"frame_bytes":0,"frames_recorded":0,"halvings":0,"loads":[{"force_n":[0.5,-0.25,0.0],"id":1,)"
            R"("moment_n_mm":[2.0,0.0,-1.0]}],"paused":false,"pictures_per_s":0.0,"rtf":0.0,"solver_error_mm":0.0375,"steps":0,)"
            R"("stopped":"","time_s":0.0,"type":"status"})");
  EXPECT_EQ(encode_live_server_message(LiveGuard{LiveGuard::Action::halved, "step halved to 0.5 ms"}),
            R"({"action":"halved","message":"step halved to 0.5 ms","type":"guard"})");
  EXPECT_EQ(encode_live_server_message(LiveGuard{LiveGuard::Action::stopped, "unstable"}),
            R"({"action":"stopped","message":"unstable","type":"guard"})");
  EXPECT_EQ(encode_live_server_message(LiveError{"message: (text): not JSON", std::nullopt}),
            R"({"message":"message: (text): not JSON","type":"error"})");
  EXPECT_EQ(encode_live_server_message(LiveError{"message: id: 7 is not a tool this page holds", 4000000000u}),
            R"({"message":"message: id: 7 is not a tool this page holds","seq":4000000000,"type":"error"})");
  EXPECT_EQ(encode_live_server_message(LiveSaved{"/tmp/s.yaml", "/tmp/s.h5", 7, 0.125, 14}),
            R"({"frames":7,"scenario":"/tmp/s.yaml","seq":14,"time_s":0.125,"trajectory":"/tmp/s.h5","type":"saved"})");
  EXPECT_EQ(encode_live_server_message(LiveSaved{"a.yaml", "a.h5", 0, 0, std::nullopt}),
            R"({"frames":0,"scenario":"a.yaml","time_s":0.0,"trajectory":"a.h5","type":"saved"})");
  EXPECT_EQ(encode_live_server_message(LiveClosed{"another browser"}), R"({"message":"another browser","type":"closed"})");
}

// What the page reads back (JSON.parse, like nlohmann's parser here) is what the server had: every
// double bit for bit, whatever its size, and the integers exactly up to their types' limits.
TEST(LiveProtocol, ServerMessagesNumbersReadBackBitForBit) {
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> exponent(-300, 300), mantissa(-1, 1);
  for (int n = 0; n < 2000; ++n) {
    const auto any_double = [&] { return mantissa(rng) * std::pow(10.0, exponent(rng)); };
    const LiveStatus s{any_double(), static_cast<int64_t>(rng()), any_double(), any_double(), any_double(),
                       n % 2 == 0, "stopped \u00b5 \"quoted\"\n", static_cast<int>(rng() % 1000), INT64_MAX - n, SIZE_MAX - n,
                       {LiveToolLoad{n, {any_double(), any_double(), any_double()}, {any_double(), any_double(), any_double()}}},
                       any_double()};
    const nlohmann::json back = nlohmann::json::parse(encode_live_server_message(s));
    ASSERT_EQ(back["type"], "status");
    EXPECT_EQ(back["time_s"].get<double>(), s.time_s);
    EXPECT_EQ(back["steps"].get<int64_t>(), s.steps);
    EXPECT_EQ(back["dt_s"].get<double>(), s.dt_s);
    EXPECT_EQ(back["rtf"].get<double>(), s.rtf);
    EXPECT_EQ(back["pictures_per_s"].get<double>(), s.pictures_per_s);
    EXPECT_EQ(back["paused"].get<bool>(), s.paused);
    EXPECT_EQ(back["stopped"].get<std::string>(), s.stopped);
    EXPECT_EQ(back["halvings"].get<int>(), s.halvings);
    EXPECT_EQ(back["frames_recorded"].get<int64_t>(), s.frames_recorded);
    EXPECT_EQ(back["frame_bytes"].get<size_t>(), s.frame_bytes);
    EXPECT_EQ(back["solver_error_mm"].get<double>(), s.solver_error_mm);
    EXPECT_EQ(back["loads"][0]["id"].get<int>(), n);
    for (size_t c = 0; c < 3; ++c) {
      EXPECT_EQ(back["loads"][0]["force_n"][c].get<double>(), s.loads[0].force_n[c]);
      EXPECT_EQ(back["loads"][0]["moment_n_mm"][c].get<double>(), s.loads[0].moment_n_mm[c]);
    }
  }
}
