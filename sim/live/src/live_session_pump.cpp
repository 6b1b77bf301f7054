// ctsurg-live's simulation thread (live_session_pump.h).
#include "live_session_pump.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/version.h"
#include "live_page_assets.h"

#include <chrono>
#include <thread>
#include <vector>

namespace ctsurg::sim {

LiveSessionPump::LiveSessionPump(LiveSession& session, const LiveServerOptions& options, LiveInbox& inbox,
                                 LiveSockets& sockets, LiveServerCounters& counters,
                                 const std::function<void(const std::string&)>& log, const std::atomic<bool>& stopping,
                                 std::atomic<bool>& unsaved)
    : session_(session),
      options_(options),
      inbox_(inbox),
      sockets_(sockets),
      counters_(counters),
      log_(log),
      stopping_(stopping),
      unsaved_(unsaved),
      clock_(1.0 / options.picture_hz, options.realtime_factor),
      last_halvings_(session.halvings()),
      window_start_(LiveWallClock::now()),
      window_frames_(counters.frames_sent.load()),
      last_status_(LiveWallClock::now() - std::chrono::seconds(1)) {
  limits_.bounds = session.rest_bounds();
  limits_.margin_mm = options.margin_mm;
  // A move travels over one tick of simulated time, the page's interval between messages.
  session.set_move_ramp_s(options.realtime_factor / options.picture_hz);
}

void LiveSessionPump::run() {
  const auto tick = std::chrono::duration<double>(1.0 / options_.picture_hz);
  while (!stopping_) {
    const auto tick_start = LiveWallClock::now();
    take_inbox();
    const LiveAdvance a = advance();
    window_sim_ += a.sim_s;
    send_picture(a.sim_s);
    send_status();
    clock_.tick_done(std::chrono::duration<double>(LiveWallClock::now() - tick_start).count(), a.wall_s);
    // The rest of the tick, if the physics left any (it takes the whole tick when it is behind).
    std::this_thread::sleep_until(tick_start + std::chrono::duration_cast<LiveWallClock::duration>(tick));
  }
}

void LiveSessionPump::take_inbox() {
  for (LiveInbound& in : inbox_.take()) {
    if (in.kind == LiveInbound::Kind::opened) {
      socket_opened(in.socket);
    } else if (in.kind == LiveInbound::Kind::closed) {
      socket_closed(in.socket);
    } else if (in.socket == current_) {
      LiveMessage m;
      if (!input_) input_ = in.received;
      try {
        m = parse_live_message(in.text, limits_);
        if (m.has_seq) last_seq_ = m.seq;
        apply(m);
      } catch (const InputError& e) {
        ++counters_.refused_messages;
        // m is the parsed message when applying it failed, the default (no seq) when parsing did.
        send(LiveError{e.what(), m.has_seq ? std::optional<uint32_t>(m.seq) : std::nullopt});
      }
    }
  }
}

// A browser took the session (over): its predecessor's tools end as if it had let go.
void LiveSessionPump::socket_opened(uint64_t socket) {
  end_tools(0, "another browser took the session over", false);
  current_ = socket;
  sent_topology_ = 0;
  send(hello());
  if (paused_by_leaving_) {
    session_.resume();
    paused_by_leaving_ = false;
  }
}

// The page went away (closed mid-drag, perhaps): its tools are let go, the session pauses once that
// is applied, and the recording so far is kept.
void LiveSessionPump::socket_closed(uint64_t socket) {
  if (socket != current_) return;
  end_tools(socket, "", false);
  current_ = 0;
  if (!session_.paused()) {
    session_.advance_events(1);
    session_.pause();
    paused_by_leaving_ = true;
  }
}

void LiveSessionPump::apply(const LiveMessage& m) {
  const auto seq = m.has_seq ? std::optional<uint32_t>(m.seq) : std::nullopt;
  switch (m.type) {
    case LiveMessage::Type::begin: {
      const int id = session_.begin_tool(live_tool_spec(m));
      tools_[id] = current_;
      unsaved_ = true;
      send(LiveBegan{id, seq});
      break;
    }
    case LiveMessage::Type::move:
      if (!tools_.count(m.id)) throw InputError("message", "id", std::to_string(m.id) + " is not a tool this page holds");
      session_.move_tool(m.id, m.position_mm);
      unsaved_ = true;
      break;
    case LiveMessage::Type::end:
      if (!tools_.count(m.id)) throw InputError("message", "id", std::to_string(m.id) + " is not a tool this page holds");
      session_.end_tool(m.id);
      tools_.erase(m.id);
      unsaved_ = true;
      break;
    case LiveMessage::Type::pause:
      session_.pause();
      break;
    case LiveMessage::Type::resume:
      session_.resume();
      break;
    case LiveMessage::Type::reset:
      end_tools(0, "the session was reset", true);
      session_.reset();
      unsaved_ = true;
      last_halvings_ = session_.halvings();
      break;
    case LiveMessage::Type::save: {
      if (options_.save_scenario.empty()) {
        throw InputError("message", "save", "this session was started without --save: it cannot write files");
      }
      session_.save(options_.save_scenario, options_.save_trajectory);
      unsaved_ = false;
      ++counters_.saves;
      log_("live: saved " + options_.save_scenario.string() + " and " + options_.save_trajectory.string() + " (" +
           std::to_string(session_.frames()) + " frames, " + std::to_string(session_.time()) + " s)");
      send(LiveSaved{options_.save_scenario.string(), options_.save_trajectory.string(), session_.frames(),
                     session_.time(), seq});
      break;
    }
  }
}

void LiveSessionPump::end_tools(uint64_t owner, const std::string& why, bool tell) {
  for (auto it = tools_.begin(); it != tools_.end();) {
    if (owner != 0 && it->second != owner) {
      ++it;
      continue;
    }
    if (session_.tool_active(it->first)) session_.end_tool(it->first);
    if (tell) send(LiveEnded{it->first, why});
    it = tools_.erase(it);
  }
}

LiveAdvance LiveSessionPump::advance() {
  if (!clock_.owed(session_.paused())) return {};
  const LiveAdvance a = session_.advance(clock_.budget_s(), clock_.advance_factor());
  clock_.advanced(a.sim_s);
  if (session_.halvings() != last_halvings_) {
    last_halvings_ = session_.halvings();
    send(LiveGuard{LiveGuard::Action::halved, session_.restart_message()});
    log_("live: " + session_.restart_message());
  }
  if (a.stopped) {
    end_tools(0, "the session stopped: " + session_.stopped_message(), true);
    send(LiveGuard{LiveGuard::Action::stopped, session_.stopped_message()});
    log_("live: " + session_.stopped_message());
  }
  return a;
}

// A picture when something changed (a quasi-static model skips ticks; a paused one stands still; the
// page's messages show in the next picture that advanced).
void LiveSessionPump::send_picture(double advanced) {
  const uint16_t flags =
      (session_.paused() ? LiveFrame::paused : 0) | (session_.stopped_message().empty() ? 0 : LiveFrame::stopped);
  if (current_ == 0 || !(advanced > 0 || sent_topology_ != session_.topology_version() || flags != last_flags_)) return;
  LiveFrame f = live_frame_of(session_, frame_number_++, sent_topology_);
  f.seq = last_seq_;
  sent_topology_ = f.topology_version;
  last_flags_ = flags;
  last_frame_bytes_ = LiveFrame::kHeaderBytes + 4 * (f.positions.size() + f.triangles.size());
  sockets_.post_frame(current_, std::move(f), input_);
  input_.reset();
}

void LiveSessionPump::send_status() {
  const auto now = LiveWallClock::now();
  const double window = std::chrono::duration<double>(now - window_start_).count();
  if (window >= 1.0) {
    rtf_ = window_sim_ / window;
    pictures_per_s_ = static_cast<double>(counters_.frames_sent.load() - window_frames_) / window;
    window_start_ = now;
    window_sim_ = 0;
    window_frames_ = counters_.frames_sent.load();
  }
  if (current_ != 0 && now - last_status_ >= std::chrono::milliseconds(250)) {
    last_status_ = now;
    send(LiveStatus{session_.time(), session_.steps(), session_.dt(), rtf_, pictures_per_s_, session_.paused(),
                    session_.stopped_message(), session_.halvings(), session_.frames(), last_frame_bytes_, session_.tool_loads(),
                    session_.solver_error_mm()});
  }
}

void LiveSessionPump::send(LiveServerMessage message) {
  sockets_.post_text(current_, encode_live_server_message(message));
}

LiveHello LiveSessionPump::hello() {
  std::vector<float> lps;
  session_.surface(lps);
  LiveHello h;
  h.scenario = session_.scenario().name;
  h.model = options_.model_description;
  h.vertex_count = lps.size() / 3;
  h.triangle_count = session_.triangles().size() / 3;
  h.bounds = session_.rest_bounds();
  h.margin_mm = options_.margin_mm;
  h.dt_s = session_.dt();
  h.colour = options_.colour;
  h.uvs = !options_.uvs.empty();
  if (!options_.normal_map_rgba.empty()) h.normal_map = std::array<int, 2>{options_.normal_map_width, options_.normal_map_height};
  h.grab_radius_mm = options_.grab_radius_mm;
  h.probe_radius_mm = options_.probe_radius_mm;
  h.cut_depth_mm = options_.cut_depth_mm;
  if (!options_.save_scenario.empty()) {
    h.save_to = std::array<std::string, 2>{options_.save_scenario.string(), options_.save_trajectory.string()};
  }
  h.library = std::string(live_page::library());
  h.version = std::string("ctsurg ") + kVersion;
  return h;
}

}  // namespace ctsurg::sim
