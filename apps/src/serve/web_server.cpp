#include "serve/web_server.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <fstream>
#include <iostream>
#include <random>
#include <regex>
#include <sstream>
#include <thread>

#include "cli_support.h"
#include "scanmesh/acquisition/calibration.h"
#include "scanmesh/acquisition/reconstruction.h"
#include "scanmesh/acquisition/session.h"
#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/drivers/camera.h"
#include "scanmesh/drivers/usb_transport.h"
#include "serve/job_runner.h"
#include "serve/web_assets.h"

// After Eigen (through the scanmesh headers): glibc's <resolv.h>, which cpp-httplib includes,
// defines the macro _res, a parameter name in Eigen's product kernels.
#include <httplib.h>

namespace scanmesh::cli::web {
namespace {

namespace fs = std::filesystem;
using httplib::Request;
using httplib::Response;

// ---------------------------------------------------------------------------------------------
// Errors as HTTP answers: the status says the kind, the JSON body says what is wrong.

struct HttpError : Error {
  HttpError(int status_code, const std::string& message) : Error(message), status(status_code) {}
  int status;
};

void send_json(Response& res, const nlohmann::json& body, int status = 200) {
  res.status = status;
  res.set_content(json_text(body), "application/json");
}

void send_error(Response& res, int status, const std::string& message) {
  send_json(res, {{"error", message}}, status);
}

// Every handler runs through this: scanmesh's typed errors become 4xx/5xx with the message,
// never a dropped connection or a dead server.
httplib::Server::Handler guarded(std::function<void(const Request&, Response&)> handler) {
  return [handler = std::move(handler)](const Request& req, Response& res) {
    try {
      handler(req, res);
    } catch (const HttpError& e) {
      send_error(res, e.status, e.what());
    } catch (const LiveRig::DevicesHeld& e) {
      send_error(res, 409, e.what());
    } catch (const InvalidInputError& e) {
      send_error(res, 400, e.what());
    } catch (const FileFormatError& e) {
      send_error(res, 422, e.what());
    } catch (const DeviceError& e) {
      send_error(res, 503, e.what());
    } catch (const IoError& e) {
      send_error(res, 500, e.what());
    } catch (const std::exception& e) {
      send_error(res, 500, std::string("internal error: ") + e.what());
    }
  };
}

nlohmann::json parse_body(const Request& req) {
  nlohmann::json body = nlohmann::json::parse(req.body, nullptr, false);
  if (body.is_discarded() || !body.is_object())
    throw HttpError(400, "the request body must be a JSON object");
  return body;
}

std::string string_field(const nlohmann::json& body, const std::string& key) {
  if (!body.contains(key) || !body[key].is_string())
    throw HttpError(400, "'" + key + "' must be given as a string");
  return body[key].get<std::string>();
}

int int_field(const nlohmann::json& body, const std::string& key, int fallback, int lo, int hi) {
  if (!body.contains(key)) return fallback;
  if (!body[key].is_number_integer() || body[key].get<long long>() < lo ||
      body[key].get<long long>() > hi)
    throw HttpError(400, "'" + key + "' must be a whole number in [" + std::to_string(lo) + ", " +
                             std::to_string(hi) + "]");
  return body[key].get<int>();
}

bool bool_field(const nlohmann::json& body, const std::string& key, bool fallback) {
  if (!body.contains(key)) return fallback;
  if (!body[key].is_boolean()) throw HttpError(400, "'" + key + "' must be true or false");
  return body[key].get<bool>();
}

// A name the page gives a new session or grid: one path component, no hidden files.
std::string checked_name(const std::string& name) {
  static const std::regex allowed("[A-Za-z0-9][A-Za-z0-9._-]{0,63}");
  if (!std::regex_match(name, allowed))
    throw HttpError(400, "name '" + name +
                             "' must be 1-64 letters, digits, '.', '_' or '-', starting with a "
                             "letter or digit");
  return name;
}

std::string random_token() {
  std::random_device device;  // /dev/urandom
  static const char* hex = "0123456789abcdef";
  std::string token;
  for (int i = 0; i < 32; ++i) token += hex[device() % 16];
  return token;
}

std::string read_whole_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw HttpError(404, "not found: " + path.filename().string());
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string content_type_of(const fs::path& path) {
  const std::string ext = path.extension().string();
  if (ext == ".png") return "image/png";
  if (ext == ".json") return "application/json";
  if (ext == ".svg") return "image/svg+xml";
  if (ext == ".yaml" || ext == ".mtl" || ext == ".obj" || ext == ".jsonl" || ext == ".txt")
    return "text/plain; charset=utf-8";
  return "application/octet-stream";
}

// Exactly the loopback names: "localhost", ::1, or a dotted IPv4 address in 127.0.0.0/8 (a
// name such as 127.evil.example is a domain, and DNS rebinding could point it here).
bool is_loopback(const std::string& host) {
  if (host == "localhost" || host == "::1") return true;
  in_addr v4{};
  return ::inet_pton(AF_INET, host.c_str(), &v4) == 1 && (ntohl(v4.s_addr) >> 24) == 127;
}

// The host part of a Host header ("localhost:8080", "[::1]:8080").
std::string host_name(const std::string& header) {
  if (header.starts_with("[")) return header.substr(1, header.find(']') - 1);
  return header.substr(0, header.find(':'));
}

// ---------------------------------------------------------------------------------------------

class WebApp {
 public:
  explicit WebApp(const ServeOptions& options);
  int run();
  void shutdown() { server_.stop(); }
  bool running() const { return server_.is_running(); }

 private:
  void install_routes();
  httplib::Server::HandlerResponse check_access(const Request& req, Response& res);

  // The data folder and what lies in it.
  fs::path data_path(const std::string& relative) const;
  fs::path sessions_dir() const { return data_ / "sessions"; }
  fs::path calibration_file() const { return data_ / "calibration.yaml"; }
  std::vector<std::string> scan_device_args() const;
  std::vector<CommandLine> reconstruct_commands(const fs::path& session, int steps,
                                                const fs::path& out) const;
  //! What a capture job runs: the recording (new or resumed), then for a scan reconstruct +
  //! mesh (with a calibration), for a calibration session calibrate (+ the check).
  struct Capture {
    int steps = 0;
    bool calibration = false;
    int poses = 3;
    bool resume = false;
    bool check = true;  //!< calibration on the simulator: check-calibration after it
  };
  std::vector<CommandLine> capture_commands(const fs::path& session, const Capture& capture) const;
  nlohmann::json session_summary(const fs::path& folder) const;

  // Handlers.
  void status(Response& res);
  void devices(Response& res);
  void live_frame(Response& res);
  void start_scan(const nlohmann::json& body, Response& res);
  void resume_scan(const nlohmann::json& body, Response& res);
  void start_calibration(const nlohmann::json& body, Response& res);
  void scan_points(const Request& req, Response& res);
  void session_frame(const Request& req, Response& res);
  void list_files(const std::string& extension, Response& res);
  void save_lines(const nlohmann::json& body, Response& res);
  void start_job(JobRequest request, Response& res, bool needs_devices);
  std::function<bool()> device_job_running() const {
    return [this] { return jobs_.busy(); };
  }

  ServeOptions options_;
  fs::path data_;
  std::string token_;  //!< empty: local only, no token
  httplib::Server server_;
  LiveRig live_;
  JobRunner jobs_;
};

WebApp::WebApp(const ServeOptions& options)
    : options_(options), live_(options.devices), jobs_(fs::read_symlink("/proc/self/exe")) {
  if (!is_loopback(options_.host) && !options_.allow_remote)
    throw InvalidInputError("--host " + options_.host +
                            " lets other machines control the scanner: add --allow-remote "
                            "(a token is then required)");
  if (options_.allow_remote) token_ = random_token();
  std::error_code ec;
  fs::create_directories(options_.data + "/sessions", ec);
  if (ec) throw IoError("cannot create '" + options_.data + "/sessions': " + ec.message());
  data_ = fs::canonical(options_.data);
  install_routes();
}

fs::path WebApp::data_path(const std::string& relative) const {
  // Only the data folder is served: a path that resolves outside it (.., an absolute path, a
  // symbolic link pointing out) is refused before anything is opened.
  if (relative.empty() || relative.find('\0') != std::string::npos)
    throw HttpError(400, "a path inside the data folder is required");
  const fs::path joined = data_ / fs::path(relative).relative_path();
  std::error_code ec;
  const fs::path resolved = fs::weakly_canonical(joined, ec);
  const std::string root = data_.string() + "/";
  if (ec || fs::path(relative).is_absolute() || !(resolved.string() + "/").starts_with(root))
    throw HttpError(403, "'" + relative + "' is outside the data folder");
  return resolved;
}

httplib::Server::HandlerResponse WebApp::check_access(const Request& req, Response& res) {
  using R = httplib::Server::HandlerResponse;
  // A page on another site can make a browser send requests to 127.0.0.1; a name that resolves
  // to 127.0.0.1 (DNS rebinding) must not be able to read the answers: only loopback names.
  if (token_.empty() && !is_loopback(host_name(req.get_header_value("Host")))) {
    send_error(res, 403, "Host '" + req.get_header_value("Host") + "' is not this machine");
    return R::Handled;
  }
  if (!token_.empty()) {
    const std::string cookie = req.get_header_value("Cookie");
    const bool ok = req.get_header_value("X-Scanmesh-Token") == token_ ||
                    req.get_param_value("token") == token_ ||
                    cookie.find("scanmesh_token=" + token_) != std::string::npos;
    if (!ok) {
      send_error(res, 401, "a token is required: open the address scanmesh serve printed");
      return R::Handled;
    }
    res.set_header("Set-Cookie", "scanmesh_token=" + token_ + "; HttpOnly; SameSite=Strict; Path=/");
  }
  // Changes only as JSON: a cross-site form cannot send that without the browser asking first.
  if (req.method == "POST" &&
      !req.get_header_value("Content-Type").starts_with("application/json")) {
    send_error(res, 415, "POST bodies must be JSON (Content-Type: application/json)");
    return R::Handled;
  }
  return R::Unhandled;
}

void WebApp::install_routes() {
  server_.set_payload_max_length(4u << 20);
  server_.set_pre_routing_handler(
      [this](const Request& req, Response& res) { return check_access(req, res); });

  for (const WebAsset& asset : web_assets()) {
    const std::string path(asset.path);
    const std::string route = path == "/index.html" ? "/" : path;
    server_.Get(route, [asset](const Request&, Response& res) {
      res.set_content(reinterpret_cast<const char*>(asset.data), asset.size,
                      std::string(asset.content_type).c_str());
      res.set_header("Cache-Control", "no-cache");
    });
  }
  // three.js from Debian's libjs-three: exactly these files, nothing else of that folder.
  const std::vector<std::pair<std::string, std::string>> three = {
      {"/three/three.min.js", "build/three.min.js"},
      {"/three/OrbitControls.js", "examples/js/controls/OrbitControls.js"},
      {"/three/PLYLoader.js", "examples/js/loaders/PLYLoader.js"},
      {"/three/OBJLoader.js", "examples/js/loaders/OBJLoader.js"}};
  for (const auto& [route, file] : three) {
    const fs::path source = fs::path(options_.three_dir) / file;
    server_.Get(route, guarded([source](const Request&, Response& res) {
                  res.set_content(read_whole_file(source), "text/javascript; charset=utf-8");
                }));
  }

  server_.Get("/api/status", guarded([this](const Request&, Response& res) { status(res); }));
  server_.Get("/api/devices", guarded([this](const Request&, Response& res) { devices(res); }));
  server_.Get("/api/live/frame",
              guarded([this](const Request&, Response& res) { live_frame(res); }));
  server_.Post("/api/live/settings", guarded([this](const Request& req, Response& res) {
                 live_.apply(parse_body(req));
                 send_json(res, live_.describe());
               }));
  server_.Post("/api/live/turn", guarded([this](const Request& req, Response& res) {
                 const nlohmann::json body = parse_body(req);
                 if (!body.contains("degrees") || !body["degrees"].is_number())
                   throw HttpError(400, "'degrees' must be a number");
                 live_.turn(body["degrees"].get<double>(), device_job_running());
                 send_json(res, live_.describe());
               }));
  server_.Post("/api/scan/start", guarded([this](const Request& req, Response& res) {
                 start_scan(parse_body(req), res);
               }));
  server_.Post("/api/scan/resume", guarded([this](const Request& req, Response& res) {
                 resume_scan(parse_body(req), res);
               }));
  server_.Get("/api/scan/points",
              guarded([this](const Request& req, Response& res) { scan_points(req, res); }));
  server_.Post("/api/calibration/start", guarded([this](const Request& req, Response& res) {
                 start_calibration(parse_body(req), res);
               }));
  server_.Post("/api/job/stop", guarded([this](const Request&, Response& res) {
                 if (!jobs_.stop()) throw HttpError(409, "no job is running");
                 send_json(res, jobs_.status());
               }));
  server_.Post("/api/job/continue", guarded([this](const Request&, Response& res) {
                 if (!jobs_.send_line("")) throw HttpError(409, "no job is waiting for input");
                 send_json(res, jobs_.status());
               }));
  server_.Get("/api/sessions", guarded([this](const Request&, Response& res) {
                nlohmann::json list = nlohmann::json::array();
                std::error_code ec;
                for (const auto& e : fs::directory_iterator(sessions_dir(), ec))
                  if (e.is_directory()) list.push_back(session_summary(e.path()));
                std::sort(list.begin(), list.end(),
                          [](const auto& a, const auto& b) { return a["name"] < b["name"]; });
                send_json(res, list);
              }));
  server_.Get("/api/sessions/frame",
              guarded([this](const Request& req, Response& res) { session_frame(req, res); }));
  server_.Post("/api/sessions/replay", guarded([this](const Request& req, Response& res) {
                 const std::string name = checked_name(string_field(parse_body(req), "session"));
                 const fs::path session = sessions_dir() / name;
                 if (!fs::exists(session / "session.json"))
                   throw HttpError(404, "no session '" + name + "'");
                 start_job({"replay",
                            {{"replay", session.string(), "--out",
                              (data_ / "results" / name / "replay").string()}},
                            name,
                            {{"out", "results/" + name + "/replay"}}},
                           res, false);
               }));
  server_.Post("/api/sessions/reconstruct", guarded([this](const Request& req, Response& res) {
                 const std::string name = checked_name(string_field(parse_body(req), "session"));
                 const fs::path session = sessions_dir() / name;
                 const SessionManifest m = read_session_manifest(session);
                 if (m.header.calibration)
                   throw HttpError(400, "'" + name + "' is a calibration session");
                 JobRequest job{"reconstruct",
                                reconstruct_commands(session,
                                                     static_cast<int>(m.header.step_count),
                                                     data_ / "results" / name),
                                name,
                                {{"out", "results/" + name}}};
                 job.folders = {(data_ / "results" / name).string()};
                 start_job(std::move(job), res, false);
               }));
  server_.Get("/api/meshes", guarded([this](const Request& req, Response& res) {
                list_files(req.get_param_value("ext") == "obj" ? ".obj" : ".ply", res);
              }));
  server_.Get("/api/grids", guarded([this](const Request&, Response& res) {
                list_files(".smg", res);
              }));
  server_.Post("/api/grids/sim", guarded([this](const Request& req, Response& res) {
                 const std::string name = checked_name(string_field(parse_body(req), "name"));
                 const fs::path dir = data_ / "grids" / name;
                 if (fs::exists(dir)) throw HttpError(409, "grids/" + name + " exists already");
                 JobRequest job{"sim-grid",
                                {{"sim", "--out", (dir / "grid.smg").string()},
                                 {"export", (dir / "grid.smg").string(), "--texture",
                                  (dir / "texture.png").string()}},
                                "",
                                {{"grid", "grids/" + name + "/grid.smg"}}};
                 job.folders = {dir.string()};
                 start_job(std::move(job), res, false);
               }));
  server_.Get("/api/lines", guarded([this](const Request& req, Response& res) {
                const fs::path grid = data_path(req.get_param_value("grid"));
                const fs::path json = grid.parent_path() / "lines.json";
                if (!fs::exists(json)) return send_json(res, {{"lines", nlohmann::json::array()}});
                res.set_content(read_whole_file(json), "application/json");
              }));
  server_.Post("/api/lines", guarded([this](const Request& req, Response& res) {
                 save_lines(parse_body(req), res);
               }));
  server_.Post("/api/animesh", guarded([this](const Request& req, Response& res) {
                 const fs::path grid = data_path(string_field(parse_body(req), "grid"));
                 const fs::path lines = grid.parent_path() / "lines.svg";
                 if (!fs::exists(lines)) throw HttpError(400, "draw and save lines first");
                 const std::string rel = fs::relative(grid.parent_path(), data_).string();
                 start_job({"animesh",
                            {{"animesh", grid.string(), "--lines", lines.string(), "--out",
                              (grid.parent_path() / "animesh").string()}},
                            "",
                            {{"out", rel + "/animesh"}}},
                           res, false);
               }));
  server_.Get(R"(/files/(.+))", guarded([this](const Request& req, Response& res) {
                const fs::path file = data_path(req.matches[1]);
                if (!fs::is_regular_file(file)) throw HttpError(404, "not found: " + std::string(req.matches[1]));
                res.set_content(read_whole_file(file), content_type_of(file).c_str());
              }));
}

int WebApp::run() {
  const int port = options_.port == 0 ? server_.bind_to_any_port(options_.host)
                                      : (server_.bind_to_port(options_.host, options_.port)
                                             ? options_.port
                                             : -1);
  if (port < 0)
    throw IoError("cannot listen on " + options_.host + ":" + std::to_string(options_.port) +
                  " (taken by another program? try --port 0)");
  const std::string host = options_.host.find(':') != std::string::npos
                               ? "[" + options_.host + "]"
                               : options_.host;
  std::cout << "scanmesh serve: http://" << host << ":" << port << "/"
            << (token_.empty() ? "" : "?token=" + token_) << "\n"
            << "  data folder " << data_.string() << ", devices "
            << (options_.devices.sim ? "simulated" : options_.devices.camera + " + " + options_.devices.board)
            << "; Ctrl-C ends\n"
            << std::flush;
  server_.listen_after_bind();
  jobs_.stop();
  jobs_.wait_idle();
  live_.release();
  return kSuccess;
}

std::vector<std::string> WebApp::scan_device_args() const {
  const DeviceChoice& d = options_.devices;
  const std::string size = std::to_string(d.width) + "x" + std::to_string(d.height);
  std::vector<std::string> args;
  if (d.sim) {
    args = {"--sim", "--time-scale", std::to_string(options_.time_scale)};
  } else {
    args = {"--device", d.camera, "--board", d.board, "--baud", std::to_string(d.baud)};
  }
  args.insert(args.end(), {"--size", size});
  if (!d.format.empty()) args.insert(args.end(), {"--format", d.format});
  return args;
}

std::vector<CommandLine> WebApp::reconstruct_commands(const fs::path& session, int steps,
                                                      const fs::path& out) const {
  if (!fs::exists(calibration_file()))
    throw HttpError(409, "no calibration yet: calibrate the scanner first (Calibration tab)");
  // One grid column per step: at two (as `demo --device-sim` uses) every second column of a
  // 90-step head scan stayed empty (docs/ui.md). 256 rows of 0.9 mm hold what a Ciclop-class
  // platter takes (< 230 mm).
  const std::string grid = (out / "grid.smg").string();
  return {{"reconstruct", session.string(), "--calib", calibration_file().string(), "--n-phi",
           std::to_string(std::max(8, steps)), "--n-h", "256", "--dh", "0.9", "--out", grid},
          {"export", grid, "--texture", (out / "texture.png").string(), "--depth",
           (out / "depth.png").string()},
          {"grid-mesh", grid, "--out", (out / "mesh.ply").string(), "--obj",
           (out / "mesh.obj").string(), "--render", (out / "render.png").string()}};
}

nlohmann::json WebApp::session_summary(const fs::path& folder) const {
  nlohmann::json j = {{"name", folder.filename().string()}};
  try {
    const SessionManifest m = read_session_manifest(folder);
    j["kind"] = m.header.calibration ? "calibration" : "scan";
    j["steps_done"] = m.steps.size();
    j["steps_planned"] = m.header.step_count;
    j["complete"] = m.steps.size() == m.header.step_count;
    j["lasers"] = m.header.laser_count;
    j["width"] = m.header.camera.width;
    j["height"] = m.header.camera.height;
    j["simulated"] = m.header.simulated;
    if (m.header.calibration && m.steps.size() < m.header.step_count)
      j["pose"] = m.header.calibration->step(m.steps.size()).first;
    if (m.header.calibration) j["poses"] = m.header.calibration->poses.size();
  } catch (const Error& e) {
    j["error"] = e.what();  // a damaged or half-created session: listed, with its problem
  }
  return j;
}

void WebApp::status(Response& res) {
  nlohmann::json j = {{"version", SCANMESH_VERSION},
                      {"data", data_.string()},
                      {"live", live_.describe()},
                      {"job", jobs_.status()},
                      {"default_steps", options_.steps},
                      {"calibration", {{"exists", fs::exists(calibration_file())}}}};
  const nlohmann::json& job = j["job"];
  if (job.contains("session") && !job["session"].get<std::string>().empty())
    j["job_session"] = session_summary(sessions_dir() / job["session"].get<std::string>());
  send_json(res, j);
}

void WebApp::devices(Response& res) {
  nlohmann::json j = {{"cameras", nlohmann::json::array()},
                      {"usb_boards", nlohmann::json::array()},
                      {"in_use", live_.describe()}};
  for (const auto& c : drivers::list_cameras())
    j["cameras"].push_back({{"path", c.path}, {"card", c.card}, {"bus", c.bus_info}});
  for (const auto& b : drivers::list_usb_boards()) {
    char id[16];
    std::snprintf(id, sizeof id, "%04x:%04x", b.vendor_id, b.product_id);
    j["usb_boards"].push_back({{"bus", b.bus}, {"address", b.address}, {"id", id}, {"kind", b.kind}});
  }
  send_json(res, j);
}

void WebApp::live_frame(Response& res) {
  const LiveFrame f = live_.frame(device_job_running());
  res.set_header("X-Peaks", std::to_string(f.peaks));
  res.set_header("X-Saturated", std::to_string(f.saturated));
  res.set_header("X-Angle", std::to_string(f.angle_deg));
  res.set_header("X-Mean-Level", std::to_string(f.mean_level));
  res.set_header("Cache-Control", "no-store");
  res.set_content(reinterpret_cast<const char*>(f.png.data()), f.png.size(), "image/png");
}

void WebApp::start_job(JobRequest request, Response& res, bool needs_devices) {
  // A capture job that goes on to reconstruct writes into results/NAME.
  for (const CommandLine& c : request.commands)
    if (c.front() == "reconstruct" && request.folders.empty())
      request.folders.push_back((data_ / "results" / fs::path(c[1]).filename()).string());
  if (jobs_.busy())
    throw HttpError(409, "a " + jobs_.status().value("kind", std::string("job")) +
                             " is running: one job at a time (stop it first)");
  bool started = false;
  if (needs_devices)
    live_.hold_for([&] { started = jobs_.start(std::move(request)); });
  else
    started = jobs_.start(std::move(request));
  if (!started) throw HttpError(409, "a job is running: one at a time");
  send_json(res, jobs_.status(), 202);
}

std::vector<CommandLine> WebApp::capture_commands(const fs::path& session, const Capture& c) const {
  CommandLine scan = {"scan", "--out", session.string()};
  if (c.resume) scan.push_back("--resume");
  if (c.calibration) {
    scan.push_back("--calibration");
    if (!c.resume) scan.insert(scan.end(), {"--poses", std::to_string(c.poses)});
  } else {
    scan.insert(scan.end(), {"--steps", std::to_string(c.steps)});
    if (options_.devices.sim && !options_.devices.scene.empty())
      scan.insert(scan.end(), {"--scene", options_.devices.scene});
  }
  const auto device = scan_device_args();
  scan.insert(scan.end(), device.begin(), device.end());
  std::vector<CommandLine> commands = {scan};
  if (c.calibration) {
    commands.push_back({"calibrate", session.string(), "--out", calibration_file().string()});
    // The verdict: re-measure the probing sphere and the dumbbell. The simulator scans them
    // with the same camera; on hardware the user records those artefacts as ordinary scans and
    // runs check-calibration on them (docs/ui.md).
    const DeviceChoice& d = options_.devices;
    if (d.sim && c.check)
      commands.push_back({"check-calibration", "--sim", "--calib", calibration_file().string(),
                          "--size", std::to_string(d.width) + "x" + std::to_string(d.height),
                          "--report", (data_ / "check-calibration.json").string()});
  } else if (fs::exists(calibration_file())) {
    const std::string name = session.filename().string();
    const auto after = reconstruct_commands(session, c.steps, data_ / "results" / name);
    commands.insert(commands.end(), after.begin(), after.end());
  }
  return commands;
}

void WebApp::start_scan(const nlohmann::json& body, Response& res) {
  const std::string name = checked_name(string_field(body, "name"));
  const int steps = int_field(body, "steps", options_.steps, 4, 3600);
  const fs::path session = sessions_dir() / name;
  if (fs::exists(session))
    throw HttpError(409, "session '" + name + "' exists: resume it or pick another name");
  start_job({"scan", capture_commands(session, {.steps = steps}), name,
             {{"steps", steps}, {"out", "results/" + name}}},
            res, true);
}

void WebApp::resume_scan(const nlohmann::json& body, Response& res) {
  const std::string name = checked_name(string_field(body, "session"));
  const fs::path session = sessions_dir() / name;
  if (!fs::exists(session / "session.json")) throw HttpError(404, "no session '" + name + "'");
  const SessionManifest m = read_session_manifest(session);
  const Capture capture{.steps = static_cast<int>(m.header.step_count),
                        .calibration = m.header.calibration.has_value(),
                        .resume = true,
                        .check = bool_field(body, "check", true)};
  start_job({capture.calibration ? "calibration" : "scan", capture_commands(session, capture),
             name, {{"steps", capture.steps}, {"out", "results/" + name}, {"resumed", true}}},
            res, true);
}

void WebApp::start_calibration(const nlohmann::json& body, Response& res) {
  const std::string name =
      checked_name(body.contains("name") ? string_field(body, "name")
                                         : "calibration-" + std::to_string(::time(nullptr)));
  const int poses = int_field(body, "poses", 3, 1, 5);
  const bool check = bool_field(body, "check", true);
  const fs::path session = sessions_dir() / name;
  if (fs::exists(session)) throw HttpError(409, "session '" + name + "' exists");
  start_job({"calibration",
             capture_commands(session, {.calibration = true, .poses = poses, .check = check}), name,
             {{"poses", poses}}},
            res, true);
}

void WebApp::scan_points(const Request& req, Response& res) {
  const std::string name = checked_name(req.get_param_value("session"));
  std::size_t from = 0;
  try {
    from = req.has_param("from") ? std::stoul(req.get_param_value("from")) : 0;
  } catch (const std::exception&) {
    throw HttpError(400, "'from' must be a step number");
  }
  if (!fs::exists(calibration_file()))
    throw HttpError(409, "no calibration yet: points appear once the scanner is calibrated");
  const Calibration calibration = Calibration::read_yaml(calibration_file());
  // The session grows while the scan records; its manifest holds only complete steps.
  const SessionReader reader(sessions_dir() / name);
  const auto& header = reader.manifest().header;
  if (header.calibration) throw HttpError(400, "'" + name + "' is a calibration session");
  if (calibration.camera.width != header.camera.width ||
      calibration.camera.height != header.camera.height)
    throw HttpError(409, "the calibration is for " + std::to_string(calibration.camera.width) + "x" +
                             std::to_string(calibration.camera.height) + " frames, the session has " +
                             std::to_string(header.camera.width) + "x" +
                             std::to_string(header.camera.height));
  const std::size_t done = reader.step_count();
  const std::size_t to = std::min(done, from + 8);  // a bounded answer; the page asks again
  std::vector<TriangulatedPoint> points;
  for (std::size_t i = from; i < to; ++i) {
    const ScanStep s = reader.step(i);
    for (int k = 0; k < std::min<int>(header.laser_count, calibration.lasers.size()); ++k) {
      const auto peaks = extract_laser_line(s.laser_on[k], s.laser_off);
      triangulate_peaks(calibration, k, s.angle_rad, peaks, &s.laser_off, points);
    }
  }
  nlohmann::json xyz = nlohmann::json::array(), rgb = nlohmann::json::array();
  for (const auto& p : points) {
    if (p.p.z() < 0.6) continue;  // the platter surface, as grid assembly leaves it out
    for (int c = 0; c < 3; ++c) xyz.push_back(std::round(p.p[c] * 100) / 100);
    rgb.insert(rgb.end(), {p.color.r, p.color.g, p.color.b});
  }
  send_json(res, {{"from", from}, {"to", to}, {"done", done},
                  {"planned", header.step_count}, {"xyz", xyz}, {"rgb", rgb}});
}

void WebApp::session_frame(const Request& req, Response& res) {
  const std::string name = checked_name(req.get_param_value("session"));
  const SessionReader reader(sessions_dir() / name);
  if (reader.step_count() == 0) throw HttpError(404, "'" + name + "' has no steps yet");
  std::size_t step = reader.step_count() - 1, k = 0;
  try {
    if (req.has_param("step")) step = std::stoul(req.get_param_value("step"));
    if (req.has_param("frame")) k = std::stoul(req.get_param_value("frame"));
  } catch (const std::exception&) {
    throw HttpError(400, "'step' and 'frame' must be numbers");
  }
  if (step >= reader.step_count() || k > static_cast<std::size_t>(reader.laser_count()))
    throw HttpError(404, "no frame " + std::to_string(k) + " of step " + std::to_string(step));
  const std::vector<std::uint8_t> png = encode_png(reader.frame(step, k), "frame");
  res.set_header("Cache-Control", "no-store");
  res.set_content(reinterpret_cast<const char*>(png.data()), png.size(), "image/png");
}

void WebApp::list_files(const std::string& extension, Response& res) {
  nlohmann::json list = nlohmann::json::array();
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(data_, ec); !ec && it != fs::recursive_directory_iterator();
       it.increment(ec)) {
    if (it->path().filename() == "sessions" && it.depth() == 0) {
      it.disable_recursion_pending();  // thousands of frames, no meshes or grids
      continue;
    }
    if (it->is_regular_file() && it->path().extension() == extension)
      list.push_back({{"path", fs::relative(it->path(), data_).string()},
                      {"bytes", it->file_size()},
                      {"has_texture", fs::exists(it->path().parent_path() / "texture.png")}});
  }
  std::sort(list.begin(), list.end(), [](const auto& a, const auto& b) { return a["path"] < b["path"]; });
  send_json(res, list);
}

// The page's lines as the SVG the CLI reads (docs/formats.md, "Animation lines"): one
// <polyline>/<polygon> per line, coordinates in texture pixels, y down from the top.
std::string lines_svg(const nlohmann::json& lines, int width, int height) {
  std::ostringstream svg;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
      << "\" viewBox=\"0 0 " << width << " " << height << "\">\n"
      << "  <!-- animation lines drawn in scanmesh serve -->\n";
  for (const auto& line : lines) {
    const bool closed = line.value("closed", false);
    svg << "  <" << (closed ? "polygon" : "polyline") << " id=\"" << line["id"].get<std::string>()
        << "\" class=\"" << line["kind"].get<std::string>() << (line.value("smooth", false) ? " smooth" : "")
        << "\" points=\"";
    bool first = true;
    for (const auto& p : line["points"]) {
      svg << (first ? "" : " ") << format_number(p[0].get<double>()) << ","
          << format_number(p[1].get<double>());
      first = false;
    }
    svg << "\" fill=\"none\" stroke=\"red\"/>\n";
  }
  svg << "</svg>\n";
  return svg.str();
}

void check_lines(const nlohmann::json& lines) {
  if (!lines.is_array() || lines.size() > 1000) throw HttpError(400, "'lines' must be a list of at most 1000 lines");
  static const std::regex id_pattern("[A-Za-z][A-Za-z0-9_-]{0,63}");
  for (const auto& line : lines) {
    if (!line.is_object() || !line.contains("id") || !line["id"].is_string() ||
        !std::regex_match(line["id"].get<std::string>(), id_pattern))
      throw HttpError(400, "every line needs an 'id' of letters, digits, '_' or '-'");
    const std::string id = line["id"].get<std::string>();
    const auto kind = line.find("kind");
    if (kind == line.end() || !kind->is_string() ||
        (*kind != "line" && *kind != "opening" && *kind != "seam"))
      throw HttpError(400, "line '" + id + "': kind must be line, opening or seam");
    for (const char* flag : {"closed", "smooth"})
      if (line.contains(flag) && !line[flag].is_boolean())
        throw HttpError(400, "line '" + id + "': '" + flag + "' must be true or false");
    if (!line.contains("points") || !line["points"].is_array() || line["points"].size() < 2 ||
        line["points"].size() > 10000)
      throw HttpError(400, "line '" + id + "' needs 2 to 10000 points");
    for (const auto& p : line["points"])
      if (!p.is_array() || p.size() != 2 || !p[0].is_number() || !p[1].is_number() ||
          !std::isfinite(p[0].get<double>()) || !std::isfinite(p[1].get<double>()) ||
          std::abs(p[0].get<double>()) > 1e5 || std::abs(p[1].get<double>()) > 1e5)
        throw HttpError(400, "line '" + id + "': points are [x, y] pairs of finite numbers");
  }
}

void WebApp::save_lines(const nlohmann::json& body, Response& res) {
  if (!body.contains("lines")) throw HttpError(400, "'lines' must be given");
  check_lines(body["lines"]);
  const fs::path grid = data_path(string_field(body, "grid"));
  if (grid.extension() != ".smg" || !fs::is_regular_file(grid))
    throw HttpError(404, "no grid '" + body["grid"].get<std::string>() + "'");
  const int width = int_field(body, "width", 512, 1, 100000);
  const int height = int_field(body, "height", 512, 1, 100000);
  if (jobs_.busy()) throw HttpError(409, "a job is running: one at a time");
  const fs::path dir = grid.parent_path();
  const std::string svg = lines_svg(body["lines"], width, height);
  write_file_atomically(dir / "lines.svg", svg);
  write_file_atomically(dir / "lines.json", json_text({{"lines", body["lines"]}}) + "\n");
  start_job({"regions",
             {{"regions", grid.string(), "--lines", (dir / "lines.svg").string(), "--png",
               (dir / "regions.png").string()}},
             "",
             {{"png", fs::relative(dir / "regions.png", data_).string()}}},
            res, false);
}

// SIGINT/SIGTERM only set this flag (async-signal-safe); a watcher thread stops the server. A
// signal that arrives before the server listens is not lost: the watcher waits for it to run.
std::atomic<bool> g_stop_requested{false};
extern "C" void request_serve_stop(int) { g_stop_requested = true; }

}  // namespace

int run_serve(const ServeOptions& options) {
  if (options.port < 0 || options.port > 65535) throw InvalidInputError("--port must be in [0, 65535]");
  // A job's pipe can close while the server writes to it, and a browser can drop a connection:
  // errors to handle, not signals that end the server.
  std::signal(SIGPIPE, SIG_IGN);
  WebApp app(options);
  g_stop_requested = false;
  std::signal(SIGINT, request_serve_stop);
  std::signal(SIGTERM, request_serve_stop);
  std::atomic<bool> finished{false};
  std::thread watcher([&] {
    while (!finished) {
      if (g_stop_requested && app.running()) app.shutdown();
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  });
  int code = kInternalError;
  try {
    code = app.run();
  } catch (...) {
    finished = true;
    watcher.join();
    throw;
  }
  finished = true;
  watcher.join();
  return code;
}

}  // namespace scanmesh::cli::web
