// scanmesh: one binary, one subcommand per pipeline stage (docs/cli.md).
#include <CLI/CLI.hpp>
#include <csignal>
#include <iostream>
#include <stdexcept>

#include "cli_support.h"
#include "commands.h"

using namespace scanmesh::cli;

int main(int argc, char** argv) {
  // A file-size limit (ulimit -f) must end a write with an error (EFBIG: exit 5, the staged
  // outputs removed), not kill the process with SIGXFSZ half way (exit 153, a texture and a
  // temporary left behind).
  std::signal(SIGXFSZ, SIG_IGN);
  CLI::App app{"scanmesh: rotary laser scans to range grids to meshes", "scanmesh"};
  app.set_version_flag("--version", SCANMESH_VERSION);
  app.require_subcommand(1);

  // Every subcommand in the order `scanmesh --help` lists them (commands.h).
  CommandList commands;
  register_grid_commands(app, commands);
  register_mesh_commands(app, commands);
  register_curvature_commands(app, commands);
  register_fans_commands(app, commands);
  register_particles_commands(app, commands);
  register_demo_commands(app, commands);
  register_vision_commands(app, commands);
  register_devices_commands(app, commands);
  register_aft_commands(app, commands);
  register_remesh_commands(app, commands);
  register_serve_commands(app, commands);
  register_measure_commands(app, commands);
  register_import_commands(app, commands);
  add_output_flags(app);  // --json and --quiet on every subcommand (docs/cli.md, "Output")

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // One clear line, then where to look; never CLI11's multi-line dump.
    std::cerr << "scanmesh: usage error: " << e.what() << " (see 'scanmesh "
              << (app.get_subcommands().empty() ? ""
                                                : app.get_subcommands().front()->get_name() + " ")
              << "--help')\n";
    return kUsageError;
  }
  set_output_mode(parsed_output_mode(app));

  return run_guarded([&] {
    for (const auto& c : commands)
      if (*c.command) return c.run();
    throw std::logic_error("a parsed subcommand without a registered run function");
  });
}
