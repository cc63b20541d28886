// CanBus: where CAN frames come from and go to. Backends:
//   - SocketCAN ("can0", "vcan0"): a raw socket on the io_context;
//   - loopback ("unix:PATH"): the same 16-byte struct can_frame over Unix datagram
//     sockets in the directory PATH, with vcan's semantics (every frame a node sends
//     reaches every other node; nodes may join and leave at any time), for hosts
//     whose kernel has no CAN support.
// Receiving is asynchronous on the caller's io_context, or polled by the caller;
// sending never blocks.
#ifndef IRSLAM_DRIVERS_CAN_BUS_H_
#define IRSLAM_DRIVERS_CAN_BUS_H_

#include <linux/can.h>

#include <boost/asio/io_context.hpp>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace irslam::drivers {

struct CanStats {
  uint64_t rx_frames = 0;
  uint64_t tx_frames = 0;
  uint64_t rx_dropped = 0;      // frames the kernel dropped (SO_RXQ_OVFL) / loopback overflow
  uint64_t tx_dropped = 0;      // frames not sent (queue full, interface down)
  uint64_t filtered = 0;        // frames received but not in the id filter (loopback only)
  uint64_t error_frames = 0;    // CAN error frames (SocketCAN only)
  uint64_t bus_off = 0;         // bus-off events (SocketCAN only)
  uint64_t link_down_events = 0;
  bool link_up = true;
  std::string last_error;       // last error-frame or I/O problem, for status
  double last_rx_time = 0;      // receive time of the last frame (CLOCK_REALTIME s)
  bool kernel_timestamps = false;  // last_rx_time came from the kernel (SO_TIMESTAMP)
};

class CanBus {
 public:
  // rx_time_s: kernel receive time (CLOCK_REALTIME seconds) when known, else 0.
  using FrameHandler = std::function<void(const can_frame& frame, double rx_time_s)>;

  virtual ~CanBus() = default;
  CanBus() = default;
  CanBus(const CanBus&) = delete;
  CanBus& operator=(const CanBus&) = delete;

  // Starts delivering received frames to `handler` on the io_context, as they arrive.
  virtual void Start(FrameHandler handler) = 0;
  // Or: frames are delivered only by Poll(), which reads everything received so
  // far without blocking (a fixed-period loop drains the bus once per period:
  // one wakeup per period instead of one per frame; rx_time_s keeps each
  // frame's kernel receive time).
  virtual void StartPolled(FrameHandler handler) = 0;
  virtual void Poll() = 0;
  // Queues a frame for transmission; false (and counted) if it could not be sent.
  virtual bool Send(const can_frame& frame) = 0;
  // Sends these frames, in order, now: what a fixed-period loop sends at the end
  // of its period (the loopback bus then needs no later turn of the loop to send
  // them together). False if any could not be sent.
  virtual bool SendNow(const std::vector<can_frame>& frames) {
    bool all = true;
    for (const can_frame& f : frames) all &= Send(f);
    return all;
  }
  virtual void Close() = 0;
  virtual const CanStats& stats() const = 0;
  virtual std::string name() const = 0;
};

struct CanBusOptions {
  std::string iface;             // "vcan0" or "unix:/run/irslam/bus"
  std::vector<uint32_t> rx_ids;  // standard ids to receive; empty = all
};

// Opens the bus named by options.iface. On failure returns nullptr and sets *error
// to a one-line explanation (e.g. "kernel has no CAN support ...").
std::unique_ptr<CanBus> OpenCanBus(boost::asio::io_context& io, const CanBusOptions& options,
                                   std::string* error);

}  // namespace irslam::drivers

#endif  // IRSLAM_DRIVERS_CAN_BUS_H_
