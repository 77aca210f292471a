// `scanmesh serve`: the local web UI (docs/ui.md). An HTTP server (cpp-httplib) serving the page
// (apps/web/, compiled in), three.js from Debian's libjs-three, and a JSON API over the live rig,
// the job runner and the data folder.
#pragma once

#include <string>

#include "serve/live_rig.h"

namespace scanmesh::cli::web {

struct ServeOptions {
  DeviceChoice devices;
  std::string host = "127.0.0.1";
  int port = 8080;  //!< 0: any free port (printed)
  bool allow_remote = false;
  std::string data = "scanmesh-data";  //!< sessions, calibration, results, lines
  std::string three_dir = "/usr/share/javascript/three";
  int steps = 90;             //!< default turntable steps of a scan started from the page
  double time_scale = 0.002;  //!< simulated devices: simulated time per real second
};

//! Runs until SIGINT/SIGTERM. Prints "scanmesh serve: http://HOST:PORT/" (with "?token=..." when
//! remote) on stdout once it listens. Throws InvalidInputError (a remote address without
//! --allow-remote, a bad port) or IoError (the port is taken, the data folder cannot be made).
int run_serve(const ServeOptions& options);

}  // namespace scanmesh::cli::web
