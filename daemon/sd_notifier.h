// systemd notification (READY=1, STATUS=..., WATCHDOG=1, STOPPING=1) without
// libsystemd's sd_notify(): that sends on a blocking socket, and a notify socket
// whose queue is full (net.unix.max_dgram_qlen) would stall the control loop. Ours
// is non-blocking: a message that does not fit now is dropped and counted.
// NOTIFY_SOCKET may be a path ("/run/...") or an abstract address ("@name").
#ifndef IRSLAM_DAEMON_SD_NOTIFIER_H_
#define IRSLAM_DAEMON_SD_NOTIFIER_H_

#include <cstdint>
#include <string>

namespace irslam {

class SdNotifier {
 public:
  // address: $NOTIFY_SOCKET as systemd gives it; empty (or not starting with '/'
  // or '@'): notifications are off and Send() does nothing.
  explicit SdNotifier(std::string address = "");
  ~SdNotifier();
  SdNotifier(SdNotifier&& other) noexcept;
  SdNotifier& operator=(SdNotifier&& other) noexcept;
  SdNotifier(const SdNotifier&) = delete;
  SdNotifier& operator=(const SdNotifier&) = delete;

  // Sends one notification datagram, never blocking; false (and counted in
  // dropped()) when it could not be sent now. The socket is opened on first use.
  bool Send(const std::string& text);

  bool enabled() const { return enabled_; }
  uint64_t dropped() const { return dropped_; }

 private:
  void Reset();

  std::string address_;
  bool enabled_ = false;
  int fd_ = -1;
  uint64_t dropped_ = 0;
};

// When to send WATCHDOG=1: every half of the watchdog interval (systemd's advice),
// measured on the daemon's clock. Pure.
class WatchdogPacer {
 public:
  explicit WatchdogPacer(uint64_t watchdog_usec) : interval_s_(static_cast<double>(watchdog_usec) * 0.5e-6) {}
  bool enabled() const { return interval_s_ > 0; }
  // True (and remembered) when a ping is due at wall time now_s.
  bool Due(double now_s) {
    if (!enabled() || now_s - last_s_ < interval_s_) return false;
    last_s_ = now_s;
    return true;
  }

 private:
  double interval_s_;
  double last_s_ = -1e18;
};

}  // namespace irslam

#endif  // IRSLAM_DAEMON_SD_NOTIFIER_H_
