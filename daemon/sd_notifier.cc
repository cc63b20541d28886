#include "daemon/sd_notifier.h"

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <utility>

namespace irslam {

SdNotifier::SdNotifier(std::string address) : address_(std::move(address)) {
  enabled_ = !address_.empty() && (address_[0] == '/' || address_[0] == '@');
}

SdNotifier::~SdNotifier() { Reset(); }

SdNotifier::SdNotifier(SdNotifier&& other) noexcept
    : address_(std::move(other.address_)),
      enabled_(other.enabled_),
      fd_(std::exchange(other.fd_, -1)),
      dropped_(other.dropped_) {
  other.enabled_ = false;
}

SdNotifier& SdNotifier::operator=(SdNotifier&& other) noexcept {
  if (this != &other) {
    Reset();
    address_ = std::move(other.address_);
    enabled_ = std::exchange(other.enabled_, false);
    fd_ = std::exchange(other.fd_, -1);
    dropped_ = other.dropped_;
  }
  return *this;
}

void SdNotifier::Reset() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

bool SdNotifier::Send(const std::string& text) {
  if (!enabled_) return false;
  if (fd_ < 0) fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (fd_ < 0) {
    ++dropped_;
    return false;
  }
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  const size_t n = std::min(address_.size(), sizeof addr.sun_path - 1);
  std::memcpy(addr.sun_path, address_.data(), n);
  if (addr.sun_path[0] == '@') addr.sun_path[0] = '\0';  // abstract namespace
  const auto len = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + n);
  if (::sendto(fd_, text.data(), text.size(), MSG_DONTWAIT | MSG_NOSIGNAL, reinterpret_cast<sockaddr*>(&addr),
               len) < 0) {
    ++dropped_;
    return false;
  }
  return true;
}

}  // namespace irslam
