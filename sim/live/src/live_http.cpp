// ctsurg-live's HTTP side (live_http.h).
#include "live_http.h"

#include "ctsurg/core/version.h"
#include "live_page_assets.h"

#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket/rfc6455.hpp>

#include <chrono>
#include <cstdio>
#include <random>

namespace ctsurg::sim {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;

namespace {

// Constant-time comparison (the time does not tell how many leading characters were right).
bool same_secret(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t k = 0; k < a.size(); ++k) diff |= static_cast<unsigned char>(a[k] ^ b[k]);
  return diff == 0;
}

// Beast's header values and targets (boost::string_view) as std::string_view.
std::string_view header_view(beast::string_view v) { return {v.data(), v.size()}; }

// One connection: the page's files under /<token>/, and the WebSocket's upgrade request.
class LiveHttpConnection : public std::enable_shared_from_this<LiveHttpConnection> {
 public:
  LiveHttpConnection(tcp::socket socket, const LiveHttpSite& site, LiveServerCounters& counters,
                     const std::function<void(const std::string&)>& log, LiveOpenSocket open_socket)
      : site_(site), counters_(counters), log_(log), open_socket_(std::move(open_socket)), stream_(std::move(socket)) {}

  void read() {
    parser_.emplace();
    parser_->header_limit(8 * 1024);
    parser_->body_limit(4 * 1024);
    stream_.expires_after(std::chrono::seconds(30));
    http::async_read(stream_, buffer_, *parser_,
                     [self = shared_from_this()](beast::error_code ec, size_t) { self->request_read(ec); });
  }

 private:
  using Response = http::response<http::string_body>;

  void request_read(beast::error_code ec) {
    if (ec == http::error::end_of_stream || ec == beast::error::timeout) {
      stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
      return;
    }
    if (ec) {  // a malformed or oversized request: answered, then closed
      ++counters_.refused_requests;
      auto r = std::make_shared<Response>(http::status::bad_request, 11);
      r->set(http::field::content_type, "text/plain; charset=utf-8");
      r->body() = "Bad request: " + ec.message() + "\n";
      r->keep_alive(false);
      r->prepare_payload();
      send(r);
      return;
    }
    ++counters_.http_requests;
    http::request<http::string_body> request = parser_->release();
    if (websocket::is_upgrade(request)) {
      const std::string refusal = socket_refusal(request);
      if (refusal.empty()) {
        open_socket_(stream_.release_socket(), std::move(request));
        return;
      }
      ++counters_.refused_requests;
      log_("live: a WebSocket was refused: " + refusal);
      send(plain(request, http::status::forbidden, refusal));
      return;
    }
    send(answer(request));
  }

  // Empty when the upgrade request may open the session's socket, else why not.
  std::string socket_refusal(const http::request<http::string_body>& request) const {
    const std::string_view host = header_view(request[http::field::host]);
    if (!site_.host_allowed(host)) return "the Host header (" + std::string(host.substr(0, 100)) + ") is not this server";
    const auto path = site_.under_token(header_view(request.target()));
    if (!path || *path != "ws") return "the socket's URL does not carry this session's token";
    const std::string_view origin = header_view(request[http::field::origin]);
    if (origin != "http://" + std::string(host)) {
      return "the Origin (" + std::string(origin.substr(0, 100)) + ") is not this server's page";
    }
    return {};
  }

  std::shared_ptr<Response> plain(const http::request<http::string_body>& request, http::status status,
                                  const std::string& text) const {
    auto r = std::make_shared<Response>(status, request.version());
    r->set(http::field::content_type, "text/plain; charset=utf-8");
    r->set(http::field::cache_control, "no-store");
    r->body() = text + "\n";
    r->keep_alive(request.keep_alive());
    r->prepare_payload();
    return r;
  }

  std::shared_ptr<Response> answer(const http::request<http::string_body>& request) const {
    if (!site_.host_allowed(header_view(request[http::field::host]))) {
      ++counters_.refused_requests;
      return plain(request, http::status::misdirected_request, "This server does not answer to that host name.");
    }
    if (request.method() != http::verb::get && request.method() != http::verb::head) {
      ++counters_.refused_requests;
      auto r = plain(request, http::status::method_not_allowed, "Only GET and HEAD.");
      r->set(http::field::allow, "GET, HEAD");
      return r;
    }
    const auto path = site_.under_token(header_view(request.target()));
    if (!path) {
      // Also a URL with the token but without its final slash: the page's relative URLs need it.
      ++counters_.refused_requests;
      return plain(request, http::status::not_found,
                   "Not found. A ctsurg-live session opens only at the full URL it printed, token included.");
    }
    std::string body, type;
    if (*path == "uvs.bin" && !site_.uvs.empty()) {
      body.assign(reinterpret_cast<const char*>(site_.uvs.data()), 4 * site_.uvs.size());
      type = "application/octet-stream";
    } else if (*path == "normal_map.bin" && !site_.normal_map_rgba.empty()) {
      body.assign(site_.normal_map_rgba.begin(), site_.normal_map_rgba.end());
      type = "application/octet-stream";
    } else {
      for (const live_page::Asset& asset : live_page::assets()) {
        if (asset.name == *path) {
          body.assign(reinterpret_cast<const char*>(asset.bytes.data()), asset.bytes.size());
          type = asset.content_type;
        }
      }
      if (type.empty()) {
        ++counters_.refused_requests;
        return plain(request, http::status::not_found, "Not found.");
      }
    }
    auto r = std::make_shared<Response>(http::status::ok, request.version());
    r->set(http::field::server, std::string("ctsurg-live ") + kVersion);
    r->set(http::field::content_type, type);
    r->set(http::field::cache_control, "no-store");
    r->set("X-Content-Type-Options", "nosniff");
    r->set("X-Frame-Options", "DENY");
    r->set("Referrer-Policy", "no-referrer");  // the token stays in this origin
    r->set("Content-Security-Policy",
           "default-src 'self'; script-src 'self'; style-src 'self'; img-src 'self' blob: data:; connect-src 'self'; "
           "base-uri 'none'; form-action 'none'; frame-ancestors 'none'");
    r->keep_alive(request.keep_alive());
    if (request.method() == http::verb::head) {
      r->content_length(body.size());
    } else {
      r->body() = std::move(body);
      r->prepare_payload();
    }
    return r;
  }

  void send(std::shared_ptr<Response> r) {
    http::async_write(stream_, *r, [self = shared_from_this(), r](beast::error_code ec, size_t) {
      if (ec) return;
      if (r->keep_alive()) {
        self->read();
      } else {
        self->stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
      }
    });
  }

  const LiveHttpSite& site_;
  LiveServerCounters& counters_;
  const std::function<void(const std::string&)>& log_;
  LiveOpenSocket open_socket_;
  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
};

}  // namespace

std::string live_random_token() {
  std::random_device device;  // /dev/urandom on Linux
  std::string token;
  for (int k = 0; k < 4; ++k) {
    char part[9];
    std::snprintf(part, sizeof part, "%08x", static_cast<unsigned>(device()));
    token += part;
  }
  return token;
}

bool LiveHttpSite::host_allowed(std::string_view host) const {
  return allowed_hosts.empty() || allowed_hosts.count(std::string(host)) > 0;
}

std::optional<std::string_view> LiveHttpSite::under_token(std::string_view target) const {
  const size_t query = target.find('?');
  if (query != std::string_view::npos) target = target.substr(0, query);
  if (target.size() < token.size() + 2 || target[0] != '/' || target[token.size() + 1] != '/') return std::nullopt;
  if (!same_secret(target.substr(1, token.size()), token)) return std::nullopt;
  return target.substr(token.size() + 2);
}

void live_http_serve(tcp::socket socket, const LiveHttpSite& site, LiveServerCounters& counters,
                     const std::function<void(const std::string&)>& log, LiveOpenSocket open_socket) {
  std::make_shared<LiveHttpConnection>(std::move(socket), site, counters, log, std::move(open_socket))->read();
}

}  // namespace ctsurg::sim
