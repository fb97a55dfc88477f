// websocketpp (Debian's libwebsocketpp-dev, header-only) on standalone Asio (libasio-dev): one
// library gives both the HTTP file server and the WebSocket API on one port, on one thread.
// cpp-httplib (also in Debian) was the other candidate; its Debian 12 version (0.11) has no
// WebSocket, and pushing 1 kHz-fed streams through HTTP polling or server-sent events would
// need a second channel for commands and base64 for camera frames.
// Built as C++17 (see web_server.hpp).
#define ASIO_STANDALONE
#include "gui/web_server.hpp"

#include <atomic>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

namespace concert::gui {

using Server = websocketpp::server<websocketpp::config::asio>;

struct WebServer::Impl {
  struct Client {
    websocketpp::connection_hdl hdl;
    std::atomic<size_t> pending{0};   // posted to the server thread, not yet handed to the socket
    std::atomic<size_t> buffered{0};  // queued on the socket (last seen)
  };

  WebServerOptions options;
  WebServerHandlers handlers;
  std::ostream& log;
  asio::io_context io;
  Server server;
  std::thread thread;
  std::mutex mutex;  // clients, by_hdl
  std::map<ClientId, std::shared_ptr<Client>> clients;
  std::map<websocketpp::connection_hdl, ClientId, std::owner_less<websocketpp::connection_hdl>> by_hdl;
  std::vector<std::unique_ptr<asio::steady_timer>> timers;
  bool stopped = false;
  ClientId next_id = 1;

  Impl(WebServerOptions o, WebServerHandlers h, std::ostream& l)
      : options(std::move(o)), handlers(std::move(h)), log(l) {}

  void serve_http(websocketpp::connection_hdl hdl) {
    Server::connection_ptr con = server.get_con_from_hdl(hdl);
    const std::string target = con->get_resource();
    const auto method = con->get_request().get_method();
    const auto file = (method == "GET" || method == "HEAD") ? resolve_request(options.roots, target)
                                                            : std::nullopt;
    if (!file) {
      con->set_status(websocketpp::http::status_code::not_found);
      con->append_header("Content-Type", "text/plain; charset=utf-8");
      con->set_body("not found: " + target + "\n");
      return;
    }
    std::ifstream in(*file, std::ios::binary);
    std::ostringstream body;
    body << in.rdbuf();
    con->set_status(websocketpp::http::status_code::ok);
    con->append_header("Content-Type", mime_type(*file));
    con->append_header("Cache-Control", "no-cache");
    con->set_body(body.str());
  }

  void repeat(asio::steady_timer& timer, int period_ms, std::function<void()> fn) {
    timer.expires_after(std::chrono::milliseconds(period_ms));
    timer.async_wait([this, &timer, period_ms, fn](const std::error_code& ec) {
      if (ec) return;
      fn();
      // Socket backlogs as seen from the server's thread (ClientSink::buffered_bytes).
      std::lock_guard<std::mutex> lock(mutex);
      for (auto& [id, c] : clients) {
        std::error_code e;
        auto con = server.get_con_from_hdl(c->hdl, e);
        if (!e) c->buffered = con->get_buffered_amount();
      }
      if (!stopped) repeat(timer, period_ms, fn);
    });
  }
};

WebServer::WebServer(WebServerOptions options, WebServerHandlers handlers, std::ostream& log)
    : impl_(std::make_unique<Impl>(std::move(options), std::move(handlers), log)) {
  Impl& m = *impl_;
  m.server.clear_access_channels(websocketpp::log::alevel::all);
  m.server.clear_error_channels(websocketpp::log::elevel::all);
  m.server.set_error_channels(websocketpp::log::elevel::fatal);
  m.server.init_asio(&m.io);
  m.server.set_reuse_addr(true);
  m.server.set_http_handler([&m](websocketpp::connection_hdl hdl) { m.serve_http(hdl); });
  m.server.set_validate_handler([&m](websocketpp::connection_hdl hdl) {
    return m.server.get_con_from_hdl(hdl)->get_resource() == "/ws";
  });
  m.server.set_open_handler([&m](websocketpp::connection_hdl hdl) {
    auto con = m.server.get_con_from_hdl(hdl);
    const std::string origin = con->get_remote_endpoint();
    auto client = std::make_shared<Impl::Client>();
    client->hdl = hdl;
    ClientId id = 0;
    {
      std::lock_guard<std::mutex> lock(m.mutex);
      id = m.next_id++;
      m.clients[id] = client;
      m.by_hdl[hdl] = id;
    }
    m.handlers.open(id, origin);
  });
  auto closed = [&m](websocketpp::connection_hdl hdl) {
    ClientId id = 0;
    {
      std::lock_guard<std::mutex> lock(m.mutex);
      auto it = m.by_hdl.find(hdl);
      if (it == m.by_hdl.end()) return;
      id = it->second;
      m.by_hdl.erase(it);
      m.clients.erase(id);
    }
    m.handlers.close(id);
  };
  m.server.set_close_handler(closed);
  m.server.set_fail_handler(closed);
  m.server.set_message_handler([&m](websocketpp::connection_hdl hdl, Server::message_ptr msg) {
    ClientId id = 0;
    {
      std::lock_guard<std::mutex> lock(m.mutex);
      auto it = m.by_hdl.find(hdl);
      if (it == m.by_hdl.end()) return;
      id = it->second;
    }
    if (msg->get_opcode() == websocketpp::frame::opcode::text) m.handlers.message(id, msg->get_payload());
  });

  std::error_code ec;
  const auto address = asio::ip::make_address(m.options.bind, ec);
  if (ec) throw std::runtime_error("--bind " + m.options.bind + ": not an IP address (" + ec.message() + ")");
  m.server.listen(asio::ip::tcp::endpoint(address, m.options.port), ec);
  if (ec) {
    throw std::runtime_error("cannot listen on " + m.options.bind + ":" + std::to_string(m.options.port) + ": " +
                             ec.message());
  }
  m.server.start_accept(ec);
  if (ec) throw std::runtime_error("cannot accept on " + m.options.bind + ": " + ec.message());
}

WebServer::~WebServer() { stop(); }

uint16_t WebServer::port() const {
  std::error_code ec;
  const auto endpoint = impl_->server.get_local_endpoint(ec);
  return ec ? 0 : endpoint.port();
}

void WebServer::every(int period_ms, std::function<void()> fn) {
  impl_->timers.push_back(std::make_unique<asio::steady_timer>(impl_->io));
  impl_->repeat(*impl_->timers.back(), period_ms, std::move(fn));
}

void WebServer::start() {
  impl_->thread = std::thread([this] { impl_->server.run(); });
}

void WebServer::stop() {
  Impl& m = *impl_;
  if (!m.thread.joinable()) return;
  asio::post(m.io, [&m] {
    m.stopped = true;
    std::error_code ec;
    m.server.stop_listening(ec);
    for (auto& t : m.timers) t->cancel();
    std::lock_guard<std::mutex> lock(m.mutex);
    for (auto& [id, c] : m.clients) {
      m.server.close(c->hdl, websocketpp::close::status::going_away, "gateway stopping", ec);
    }
  });
  // Closing handshakes get a moment; then the loop stops whatever is left.
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  m.server.stop();
  m.thread.join();
}

void WebServer::send(ClientId client, std::string message, bool binary) {
  Impl& m = *impl_;
  std::shared_ptr<Impl::Client> c;
  {
    std::lock_guard<std::mutex> lock(m.mutex);
    auto it = m.clients.find(client);
    if (it == m.clients.end()) return;
    c = it->second;
  }
  const size_t size = message.size();
  c->pending += size;
  asio::post(m.io, [&m, c, size, text = std::move(message), binary] {
    std::error_code ec;
    m.server.send(c->hdl, text, binary ? websocketpp::frame::opcode::binary : websocketpp::frame::opcode::text,
                  ec);
    auto con = m.server.get_con_from_hdl(c->hdl, ec);
    if (!ec) c->buffered = con->get_buffered_amount();
    c->pending -= size;
  });
}

size_t WebServer::buffered_bytes(ClientId client) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  auto it = impl_->clients.find(client);
  return it == impl_->clients.end() ? 0 : it->second->pending + it->second->buffered;
}

}  // namespace concert::gui
