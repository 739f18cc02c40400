#include "hal/linux/socketcan.hpp"

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <stdexcept>

namespace gyrochar::hal {

namespace {

// The interface's index, or 0 when there is no such interface now.
int interface_index(int fd, const std::string& name) {
  ifreq ifr{};
  std::strncpy(ifr.ifr_name, name.c_str(), IFNAMSIZ - 1);
  return ioctl(fd, SIOCGIFINDEX, &ifr) < 0 ? 0 : ifr.ifr_ifindex;
}

std::uint64_t monotonic_ms() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000u + static_cast<std::uint64_t>(ts.tv_nsec) / 1000000u;
}

}  // namespace

SocketCan::SocketCan(const std::string& interface) : name_(interface) {
  if (interface.empty() || interface.size() >= IFNAMSIZ)
    throw std::runtime_error(interface + ": not a valid interface name");
  fd_ = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd_ < 0) throw std::runtime_error(interface + ": cannot open a CAN socket: " + std::strerror(errno));
  ifindex_ = interface_index(fd_, interface);
  if (ifindex_ == 0) {
    const int e = errno;
    close(fd_);
    throw std::runtime_error(interface + ": " + std::strerror(e));
  }
  const can_err_mask_t errors = CAN_ERR_MASK;
  setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errors, sizeof errors);
  const int on = 1;
  setsockopt(fd_, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on);
  setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on);  // refused on classic-only: fine
  // A receive queue of some thousands of frames instead of the default few hundred, so that a
  // reader that is not scheduled for a while loses nothing. FORCE passes net.core.rmem_max with
  // CAP_NET_ADMIN; without it the plain option is capped there.
  const int rcvbuf = 4 << 20;
  if (setsockopt(fd_, SOL_SOCKET, SO_RCVBUFFORCE, &rcvbuf, sizeof rcvbuf) != 0)
    setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
  // Bound to every CAN interface (index 0), sending to and keeping frames of ours by index: an
  // interface that vanishes and comes back (a USB adapter re-plugged) gets a new index, which
  // send() finds again without a new socket, so the descriptor the caller polls stays valid.
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = 0;
  if (bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) < 0) {
    const int e = errno;
    close(fd_);
    throw std::runtime_error(interface + ": " + std::strerror(e));
  }
}

SocketCan::~SocketCan() {
  if (fd_ >= 0) close(fd_);
}

SendResult SocketCan::send(const CanFrame& f) {
  if (ifindex_ == 0) {  // vanished: look for it again, at most once a second
    const std::uint64_t now = monotonic_ms();
    if (now - last_lookup_ms_ >= 1000) {
      last_lookup_ms_ = now;
      ifindex_ = interface_index(fd_, name_);
    }
    if (ifindex_ == 0) {
      ++counters_.tx_dropped;
      return SendResult::bus_down;
    }
  }
  canfd_frame raw{};
  raw.can_id = f.id | (f.extended ? CAN_EFF_FLAG : 0u);
  raw.len = f.len;
  std::memcpy(raw.data, f.data.data(), f.len);
  const std::size_t size = f.fd ? CANFD_MTU : CAN_MTU;
  sockaddr_can to{};
  to.can_family = AF_CAN;
  to.can_ifindex = ifindex_;
  if (sendto(fd_, &raw, size, 0, reinterpret_cast<const sockaddr*>(&to), sizeof to) == static_cast<ssize_t>(size)) {
    ++counters_.sent;
    // The queue takes frames again: the interface is up and the controller out of bus-off.
    if (state_ == BusState::down || state_ == BusState::bus_off) state_ = BusState::active;
    return SendResult::sent;
  }
  ++counters_.tx_dropped;
  if (errno == ENODEV || errno == ENXIO) ifindex_ = 0;  // the interface is gone
  if (errno == ENETDOWN || errno == ENXIO || errno == ENODEV) {
    state_ = BusState::down;
    return SendResult::bus_down;
  }
  return SendResult::queue_full;
}

bool SocketCan::set_filters(std::span<const CanFilter> filters) {
  constexpr std::size_t max_filters = 16;
  if (filters.size() > max_filters) return false;
  can_filter raw[max_filters];
  for (std::size_t k = 0; k < filters.size(); ++k)
    raw[k] = {(filters[k].id & CAN_EFF_MASK) | CAN_EFF_FLAG, (filters[k].mask & CAN_EFF_MASK) | CAN_EFF_FLAG | CAN_RTR_FLAG};
  return setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FILTER, filters.empty() ? nullptr : raw,
                    static_cast<socklen_t>(filters.size() * sizeof(can_filter))) == 0;
}

std::optional<CanFrame> SocketCan::receive() {
  canfd_frame raw{};
  iovec iov{&raw, sizeof raw};
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(std::uint32_t))];
  sockaddr_can from{};
  msghdr msg{};
  ssize_t n = 0;
  for (int skipped = 0;; ++skipped) {  // frames of other CAN interfaces and remote frames are not ours: skip them
    msg = msghdr{};
    msg.msg_name = &from;
    msg.msg_namelen = sizeof from;
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof control;
    n = recvmsg(fd_, &msg, MSG_DONTWAIT);
    if (n < static_cast<ssize_t>(CAN_MTU)) {
      if (n < 0 && (errno == ENETDOWN || errno == ENODEV)) state_ = BusState::down;
      return std::nullopt;
    }
    // A remote (RTR) frame is a request for data and carries none: it is nobody's data frame.
    const bool remote = (raw.can_id & CAN_RTR_FLAG) != 0 && (raw.can_id & CAN_ERR_FLAG) == 0;
    if (remote) {
      if (skipped == 255) return std::nullopt;
      continue;
    }
    if (from.can_ifindex == ifindex_) break;
    // Ours may have come back under a new index (a receive-only user never sends to find out).
    if (const std::uint64_t now = monotonic_ms(); now - last_lookup_ms_ >= 1000) {
      last_lookup_ms_ = now;
      if (const int index = interface_index(fd_, name_); index != 0) ifindex_ = index;
      if (from.can_ifindex == ifindex_) break;
    }
    if (skipped == 255) return std::nullopt;  // bounded: the descriptor stays readable
  }
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) {
      std::uint32_t dropped = 0;
      std::memcpy(&dropped, CMSG_DATA(c), sizeof dropped);
      counters_.rx_dropped = dropped;  // the kernel's running total for this socket
    }
  }
  CanFrame f;
  f.fd = n == static_cast<ssize_t>(CANFD_MTU);
  f.extended = (raw.can_id & CAN_EFF_FLAG) != 0;
  f.error = (raw.can_id & CAN_ERR_FLAG) != 0;
  f.id = raw.can_id & (f.extended || f.error ? CAN_EFF_MASK : CAN_SFF_MASK);
  f.len = raw.len > 64 ? 64 : raw.len;
  std::memcpy(f.data.data(), raw.data, f.len);
  if (f.error) {
    ++counters_.error_frames;
#ifdef CAN_ERR_CNT
    if ((f.id & CAN_ERR_CNT) && f.len >= 8) {
      counters_.tx_error_counter = raw.data[6];
      counters_.rx_error_counter = raw.data[7];
    }
#endif
    if (f.id & CAN_ERR_BUSOFF) {
      if (state_ != BusState::bus_off) ++counters_.bus_off_events;
      state_ = BusState::bus_off;
    } else if (f.id & CAN_ERR_RESTARTED) {
      state_ = BusState::active;
    } else if ((f.id & CAN_ERR_CRTL) && f.len > 1) {
      if (raw.data[1] & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) state_ = BusState::passive;
      else if (raw.data[1] & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) state_ = BusState::warning;
      else if (raw.data[1] & CAN_ERR_CRTL_ACTIVE) state_ = BusState::active;
    }
  } else {
    ++counters_.received;
  }
  return f;
}

}  // namespace gyrochar::hal
