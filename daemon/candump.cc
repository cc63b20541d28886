// irslam-candump: print the frames of a bus in candump's -L log format, for buses
// candump cannot open (the loopback bus) and alike on SocketCAN.
//   irslam-candump IFACE [-n COUNT]
// Each line: "(seconds.micros) IFACE ID#DATA", decodable with proto/irslam.dbc.
#include <CLI/CLI.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/signal_set.hpp>
#include <cstdio>
#include <ctime>

#include "drivers/can_bus.h"
#include "proto/codec.h"

int main(int argc, char** argv) {
  CLI::App app{"irslam-candump: print bus frames in candump -L format"};
  std::string iface;
  long count = 0;
  app.add_option("iface", iface, "vcan0, can0 or unix:PATH")->required();
  app.add_option("-n", count, "Exit after this many frames (default: run until interrupted)");
  CLI11_PARSE(app, argc, argv);
  boost::asio::io_context io;
  std::string error;
  auto bus = irslam::drivers::OpenCanBus(io, {iface, {}}, &error);
  if (!bus) {
    std::fprintf(stderr, "irslam-candump: %s\n", error.c_str());
    return 1;
  }
  const std::string name = iface.rfind("unix:", 0) == 0 ? "loopback" : iface;
  long seen = 0;
  bus->Start([&](const can_frame& f, double rx) {
    if (count > 0 && seen >= count) return;  // the rest of a batch after the last one
    if (rx <= 0) {
      timespec ts;
      ::clock_gettime(CLOCK_REALTIME, &ts);
      rx = static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
    }
    std::printf("(%.6f) %s %s\n", rx, name.c_str(), irslam::proto::ToCandumpString(f).c_str());
    std::fflush(stdout);
    if (count > 0 && ++seen >= count) io.stop();
  });
  boost::asio::signal_set signals(io, SIGINT, SIGTERM);
  signals.async_wait([&](const boost::system::error_code&, int) { io.stop(); });
  io.run();
  return 0;
}
