#pragma once
// Where the master's frames go: a raw Ethernet socket on a named interface (AF_PACKET, EtherType
// 0x88A4), or, in tests, a function that answers in-process.

#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "concert/ethercat/frame.hpp"

namespace concert::ethercat {

/// A link that cannot be opened or used; what() names the interface and the system error.
class LinkError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Sends frames and receives the EtherCAT frames coming back (never the link's own sends).
class Link {
 public:
  virtual ~Link() = default;
  /// Sends one frame's bytes. Throws LinkError.
  virtual void send(std::span<const uint8_t> frame) = 0;
  /// The next EtherCAT frame received within `timeout`, or nothing. Its bytes stay valid until
  /// the next call. Throws LinkError.
  virtual std::optional<std::span<const uint8_t>> receive(std::chrono::microseconds timeout) = 0;
  /// For messages: "eth0", "in-process ring".
  virtual std::string name() const = 0;
  /// The source address of the frames sent (the interface's), if the link has one.
  virtual std::optional<MacAddress> address() const { return std::nullopt; }
};

/// A raw socket bound to one interface, receiving EtherType 0x88A4 only. Needs CAP_NET_RAW.
class RawSocketLink final : public Link {
 public:
  /// Opens the socket on `ifname`. Throws LinkError: no such interface, not permitted (not root
  /// and no CAP_NET_RAW), interface down.
  explicit RawSocketLink(const std::string& ifname);
  ~RawSocketLink() override;
  RawSocketLink(const RawSocketLink&) = delete;
  RawSocketLink& operator=(const RawSocketLink&) = delete;

  void send(std::span<const uint8_t> frame) override;
  std::optional<std::span<const uint8_t>> receive(std::chrono::microseconds timeout) override;
  std::string name() const override { return ifname_; }
  /// The interface's MAC address (the source address of the frames sent).
  const MacAddress& mac() const { return mac_; }
  std::optional<MacAddress> address() const override { return mac_; }

 private:
  std::string ifname_;
  int fd_ = -1;
  int ifindex_ = 0;
  MacAddress mac_{};
  std::vector<uint8_t> buffer_;
};

/// A link whose every sent frame is answered at once by `answer` (an in-process virtual ring);
/// answer returning nothing = the frame was lost.
class LoopbackLink final : public Link {
 public:
  using Answer = std::function<std::optional<std::vector<uint8_t>>(std::span<const uint8_t>)>;
  explicit LoopbackLink(Answer answer) : answer_(std::move(answer)) {}
  void send(std::span<const uint8_t> frame) override;
  std::optional<std::span<const uint8_t>> receive(std::chrono::microseconds timeout) override;
  std::string name() const override { return "in-process ring"; }

 private:
  Answer answer_;
  std::vector<std::vector<uint8_t>> pending_;
  std::vector<uint8_t> current_;
};

}  // namespace concert::ethercat
