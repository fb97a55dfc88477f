#include "concert/ethercat/link.hpp"

#include <arpa/inet.h>
#include <linux/if_packet.h>
#include <net/ethernet.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace concert::ethercat {
namespace {

std::string system_error(const std::string& what, int error) {
  return what + ": " + std::strerror(error);
}

}  // namespace

RawSocketLink::RawSocketLink(const std::string& ifname) : ifname_(ifname), buffer_(kMaxFrameBytes + 64) {
  if (ifname.empty() || ifname.size() >= IFNAMSIZ) {
    throw LinkError("interface name '" + ifname + "' is empty or longer than " +
                    std::to_string(IFNAMSIZ - 1) + " characters");
  }
  fd_ = ::socket(AF_PACKET, SOCK_RAW | SOCK_CLOEXEC, htons(kEtherType));
  if (fd_ < 0) {
    const int error = errno;
    throw LinkError(system_error("raw EtherCAT socket on " + ifname +
                                     (error == EPERM ? " (needs root or CAP_NET_RAW)" : ""),
                                 error));
  }
  ifreq request{};
  std::strncpy(request.ifr_name, ifname.c_str(), IFNAMSIZ - 1);
  if (::ioctl(fd_, SIOCGIFINDEX, &request) < 0) {
    const int error = errno;
    ::close(fd_);
    throw LinkError(system_error("interface '" + ifname + "'", error));
  }
  ifindex_ = request.ifr_ifindex;
  if (::ioctl(fd_, SIOCGIFHWADDR, &request) == 0) {
    std::memcpy(mac_.data(), request.ifr_hwaddr.sa_data, 6);
  }
  if (::ioctl(fd_, SIOCGIFFLAGS, &request) == 0 && (request.ifr_flags & IFF_UP) == 0) {
    ::close(fd_);
    throw LinkError("interface '" + ifname + "' is down (ip link set " + ifname + " up)");
  }
  sockaddr_ll address{};
  address.sll_family = AF_PACKET;
  address.sll_protocol = htons(kEtherType);
  address.sll_ifindex = ifindex_;
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) < 0) {
    const int error = errno;
    ::close(fd_);
    throw LinkError(system_error("binding the EtherCAT socket to " + ifname, error));
  }
}

RawSocketLink::~RawSocketLink() {
  if (fd_ >= 0) ::close(fd_);
}

void RawSocketLink::send(std::span<const uint8_t> frame) {
  const ssize_t sent = ::send(fd_, frame.data(), frame.size(), 0);
  if (sent < 0) throw LinkError(system_error("sending on " + ifname_, errno));
  if (static_cast<std::size_t>(sent) != frame.size()) {
    throw LinkError("sending on " + ifname_ + ": " + std::to_string(sent) + " of " +
                    std::to_string(frame.size()) + " bytes sent");
  }
}

std::optional<std::span<const uint8_t>> RawSocketLink::receive(std::chrono::microseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (true) {
    const auto left = std::chrono::duration_cast<std::chrono::microseconds>(
        deadline - std::chrono::steady_clock::now());
    pollfd p{fd_, POLLIN, 0};
    timespec wait{};
    if (left.count() > 0) {
      wait.tv_sec = static_cast<time_t>(left.count() / 1000000);
      wait.tv_nsec = static_cast<long>((left.count() % 1000000) * 1000);
    }
    const int ready = ::ppoll(&p, 1, &wait, nullptr);
    if (ready < 0) {
      if (errno == EINTR) return std::nullopt;
      throw LinkError(system_error("waiting on " + ifname_, errno));
    }
    if (ready == 0) return std::nullopt;
    sockaddr_ll from{};
    socklen_t from_size = sizeof from;
    const ssize_t got = ::recvfrom(fd_, buffer_.data(), buffer_.size(), MSG_DONTWAIT,
                                   reinterpret_cast<sockaddr*>(&from), &from_size);
    if (got < 0) {
      if (errno == EAGAIN || errno == EINTR) continue;
      throw LinkError(system_error("receiving on " + ifname_, errno));
    }
    // A packet socket also sees the frames this host sends on the interface: skip them.
    if (from.sll_pkttype == PACKET_OUTGOING) continue;
    if (got < static_cast<ssize_t>(kEthernetHeaderBytes)) continue;
    return std::span<const uint8_t>(buffer_.data(), static_cast<std::size_t>(got));
  }
}

void LoopbackLink::send(std::span<const uint8_t> frame) {
  if (auto answer = answer_(frame)) pending_.push_back(std::move(*answer));
}

std::optional<std::span<const uint8_t>> LoopbackLink::receive(std::chrono::microseconds) {
  if (pending_.empty()) return std::nullopt;
  current_ = std::move(pending_.front());
  pending_.erase(pending_.begin());
  return std::span<const uint8_t>(current_);
}

}  // namespace concert::ethercat
