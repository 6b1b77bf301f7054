// Tests for ctsurg/sim/live/live_protocol.h: every client message parsed; malformed, oversized and
// out-of-range messages refused with the field named; random and mutated bytes only ever parsed or
// refused (an InputError, never another exception); binary frames round-trip bit for bit, with and
// without triangles, and damaged frames are refused.
#include "ctsurg/sim/live/live_protocol.h"

#include "ctsurg/core/error.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
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
