// `scanmesh serve`: the local web UI (docs/ui.md).
#include <CLI/CLI.hpp>
#include <filesystem>

#include "cli_support.h"
#include "scanmesh/core/errors.h"
#include "commands.h"
#include "serve/web_server.h"
#include "sim_rig.h"

namespace scanmesh::cli {

void register_serve_commands(CLI::App& app, CommandList& commands) {
  auto o = std::make_shared<web::ServeOptions>();
  auto size = std::make_shared<std::string>("640x480");
  CLI::App* serve = app.add_subcommand(
      "serve", "Web UI in the browser: live view, scan, calibrate, sessions, meshes, animation lines");
  serve->add_flag("--sim", o->devices.sim, "Use the simulated camera and board");
  serve->add_option("--device", o->devices.camera, "Camera: /dev/videoN or its card name");
  serve->add_option("--board", o->devices.board, "Board: /dev/ttyACM0, VID:PID or usb:BUS:ADDR");
  serve->add_option("--baud", o->devices.baud, "Serial baud rate")->capture_default_str()
      ->check(in_range(300, 4000000));
  serve->add_option("--size", *size, "Frame size WIDTHxHEIGHT of live view, scans and calibration")
      ->capture_default_str();
  serve->add_option("--format", o->devices.format, "Camera format: yuyv | mjpeg | rgb24");
  serve->add_option("--scene", o->devices.scene,
                    "--sim: what stands on the table: head, a scene YAML, or synthetic (a fast "
                    "line pattern)")
      ->capture_default_str();
  serve->add_option("--port", o->port, "TCP port (0: any free port)")->capture_default_str()
      ->check(in_range(0, 65535));
  serve->add_option("--host", o->host,
                    "Address to listen on (only 127.0.0.1 / ::1 without --allow-remote)")
      ->capture_default_str();
  serve->add_flag("--allow-remote", o->allow_remote,
                  "Allow a non-loopback --host; every request then needs the printed token");
  serve->add_option("--data", o->data, "Folder of sessions, calibration and results")
      ->capture_default_str();
  serve->add_option("--steps", o->steps, "Default turntable steps of a scan")
      ->capture_default_str()
      ->check(in_range(4, 3600));
  serve->add_option("--time-scale", o->time_scale,
                    "Simulation: simulated time per real second of scans")
      ->capture_default_str()
      ->check(above(0, 1));
  serve->add_option("--three", o->three_dir, "three.js folder (Debian's libjs-three)")
      ->capture_default_str();
  commands.push_back({serve, [o, size] {
                        if (o->devices.sim == (!o->devices.camera.empty() || !o->devices.board.empty()))
                          throw InvalidInputError("give either --sim or both --device and --board");
                        if (!o->devices.sim && (o->devices.camera.empty() || o->devices.board.empty()))
                          throw InvalidInputError("real devices need --device CAM and --board BOARD");
                        std::tie(o->devices.width, o->devices.height) = parse_frame_size(*size);
                        if (o->devices.scene == "synthetic") o->devices.scene.clear();
                        if (!o->devices.scene.empty() && o->devices.scene != "head" &&
                            !std::filesystem::is_regular_file(o->devices.scene))
                          throw InvalidInputError("--scene '" + o->devices.scene +
                                                  "' is neither head, synthetic nor a scene file");
                        return web::run_serve(*o);
                      }});
}

}  // namespace scanmesh::cli
