// live_frame_of (live_protocol.h): a LiveSession's surface as a frame. Apart from the protocol's parser
// and codec (live_protocol.cpp) so that those build with core alone (tests/fuzz/fuzz_live_message.cpp).
#include "ctsurg/sim/live/live_protocol.h"
#include "ctsurg/sim/live/live_session.h"

namespace ctsurg::sim {

LiveFrame live_frame_of(LiveSession& session, uint64_t frame, uint64_t sent_topology) {
  LiveFrame f;
  f.frame = frame;
  f.time_s = session.time();
  f.steps = session.steps();
  f.topology_version = session.topology_version();
  session.surface(f.positions);
  const std::vector<uint32_t>& tris = session.triangles();
  f.triangle_count = static_cast<uint32_t>(tris.size() / 3);
  if (f.topology_version != sent_topology) {
    f.flags |= LiveFrame::triangles_follow;
    f.triangles = tris;
  }
  if (session.paused()) f.flags |= LiveFrame::paused;
  if (!session.stopped_message().empty()) f.flags |= LiveFrame::stopped;
  return f;
}

}  // namespace ctsurg::sim
