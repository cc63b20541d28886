// irslam-foxglove: the live view of irslamd in Foxglove (docs/foxglove.md). A client
// of irslamd's control socket that serves the Foxglove WebSocket protocol.
//   irslam-foxglove [--socket PATH] [--listen 127.0.0.1:8765] [--config FILE]
#include <CLI/CLI.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/address.hpp>
#include <boost/asio/signal_set.hpp>
#include <csignal>
#include <cstdio>
#include <filesystem>

#include "daemon/config.h"
#include "daemon/foxglove_bridge.h"
#include "daemon/foxglove_server.h"
#include "daemon/rpc_client.h"

namespace {

namespace asio = boost::asio;
using irslam::foxglove::Bridge;
using irslam::foxglove::BridgeOptions;
using irslam::foxglove::Server;

constexpr const char* kDefaultConfig = "/etc/irslam/irslamd.conf";

// HOST:PORT, HOST an IPv4 address or [IPv6]; port 0 picks a free one.
bool ParseListen(const std::string& text, asio::ip::tcp::endpoint* ep, std::string* error) {
  const auto colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == text.size()) {
    *error = "--listen wants HOST:PORT, e.g. 127.0.0.1:8765";
    return false;
  }
  std::string host = text.substr(0, colon);
  if (host.size() > 2 && host.front() == '[' && host.back() == ']')
    host = host.substr(1, host.size() - 2);
  if (host == "localhost") host = "127.0.0.1";
  boost::system::error_code ec;
  const auto addr = asio::ip::make_address(host, ec);
  if (ec) {
    *error = "--listen: not an IP address: " + host;
    return false;
  }
  const std::string port_text = text.substr(colon + 1);
  char* end = nullptr;
  const long port = std::strtol(port_text.c_str(), &end, 10);
  if (*end != '\0' || port < 0 || port > 65535) {
    *error = "--listen: not a port: " + port_text;
    return false;
  }
  *ep = asio::ip::tcp::endpoint(addr, static_cast<unsigned short>(port));
  return true;
}

// The IR sensor mounts, range and robot radius from irslamd's config (the
// default one when it exists and none is named).
bool LoadRobot(std::string config_path, irslam::foxglove::RobotShape* robot, std::string* error) {
  irslam::robot::CoreOptions core = irslam::robot::DefaultCoreOptions();
  if (config_path.empty() && std::filesystem::exists(kDefaultConfig)) config_path = kDefaultConfig;
  if (!config_path.empty() && !irslam::LoadCoreConfigFile(config_path, &core, error)) return false;
  robot->mounts = core.slam.mounts;
  robot->max_range_m = core.ir.max_range_m;
  robot->radius_m = core.slam.geometry.radius_m;
  return true;
}

// Listens on `endpoint` and says where; false after a message.
bool Listen(Server* server, const asio::ip::tcp::endpoint& endpoint,
            const std::string& socket_path) {
  std::string error;
  if (!server->Listen(endpoint, &error)) {
    std::fprintf(stderr, "<3>irslam-foxglove: %s\n", error.c_str());
    return false;
  }
  if (!endpoint.address().is_loopback()) {
    std::fprintf(
        stderr,
        "<4>foxglove: listening on %s, not loopback: anyone who reaches it sees the robot's data\n",
        endpoint.address().to_string().c_str());
  }
  const auto local = server->local_endpoint();
  const std::string host = local.address().is_v6() ? "[" + local.address().to_string() + "]"
                                                   : local.address().to_string();
  std::fprintf(stderr, "<6>foxglove: listening on ws://%s:%u (irslamd at %s)\n", host.c_str(),
               static_cast<unsigned>(local.port()), socket_path.c_str());
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"irslam-foxglove: irslamd's live view in Foxglove (Foxglove WebSocket protocol)"};
  std::string socket_path = irslam::DefaultSocketPath();
  std::string listen = "127.0.0.1:8765";
  std::string config_path;
  double rate = 10, map_period = 1;
  app.add_option("--socket", socket_path,
                 "irslamd's control socket ($IRSLAM_SOCKET, else /run/irslam/irslamd.sock)");
  app.add_option("--listen", listen, "address:port of the WebSocket server (loopback by default)")
      ->capture_default_str();
  app.add_option("--config", config_path,
                 "irslamd's config, for the IR sensor mounts (default: /etc/irslam/irslamd.conf "
                 "when it exists)");
  app.add_option("--rate", rate, "status rate asked of irslamd, Hz")
      ->check(CLI::Range(0.1, 50.0))
      ->capture_default_str();
  app.add_option("--map-period", map_period, "map poll period while a map topic is watched, s")
      ->check(CLI::Range(0.1, 60.0))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  std::string error;
  asio::ip::tcp::endpoint endpoint;
  if (!ParseListen(listen, &endpoint, &error)) {
    std::fprintf(stderr, "irslam-foxglove: %s\n", error.c_str());
    return 2;
  }
  BridgeOptions options;
  options.socket_path = socket_path;
  options.status_rate_hz = rate;
  options.map_period_s = map_period;
  if (!LoadRobot(config_path, &options.robot, &error)) {
    std::fprintf(stderr, "irslam-foxglove: %s\n", error.c_str());
    return 2;
  }

  asio::io_context io;
  Server server(io, irslam::foxglove::IrslamChannels());
  if (!Listen(&server, endpoint, socket_path)) return 1;

  Bridge bridge(io, &server, options);
  bridge.Start();

  asio::signal_set signals(io, SIGINT, SIGTERM);
  signals.async_wait([&](const boost::system::error_code& ec, int signo) {
    if (ec) return;
    std::fprintf(stderr, "<6>foxglove: signal %d: stopping\n", signo);
    bridge.Stop();
    server.Close();
    io.stop();
  });
  std::signal(SIGPIPE, SIG_IGN);
  io.run();
  const auto& st = server.stats();
  std::fprintf(
      stderr,
      "<6>foxglove: clients %llu, refused %llu, bad input %llu, messages sent %llu, dropped %llu\n",
      static_cast<unsigned long long>(st.accepted), static_cast<unsigned long long>(st.rejected),
      static_cast<unsigned long long>(st.bad_input), static_cast<unsigned long long>(st.sent),
      static_cast<unsigned long long>(st.dropped));
  return 0;
}
