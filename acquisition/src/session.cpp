#include "scanmesh/acquisition/session.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <nlohmann/json.hpp>
#include <numbers>
#include <type_traits>
#include <utility>

#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/binary_io.h"
#include "scanmesh/core/errors.h"

namespace scanmesh {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kFormatName = "scanmesh-session";
constexpr std::size_t kMaxSteps = 1u << 20;
constexpr int kMaxLasers = 8;

std::string storage_name(FrameStorage s) { return s == FrameStorage::Png ? "png" : "mjpeg"; }

std::uint32_t pixels_crc(const Image8& img) {
  return crc32_of(img.pixels.data(), img.pixels.size());
}

void fsync_path(const fs::path& p, bool directory) {
  const int fd = ::open(p.c_str(), (directory ? O_RDONLY | O_DIRECTORY : O_RDONLY) | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

std::string frame_file_name(std::size_t step, std::size_t k, FrameStorage storage) {
  char name[64];
  const char* ext = storage == FrameStorage::Png ? "png" : "jpg";
  if (k == 0)
    std::snprintf(name, sizeof name, "frames/%06zu_off.%s", step, ext);
  else
    std::snprintf(name, sizeof name, "frames/%06zu_laser%zu.%s", step, k - 1, ext);
  return name;
}

// Typed getters that turn every json type or range problem into a FileFormatError.
// Integer fields must be json integers that fit T: nlohmann converts a float such as
// 1.7e11 to int with a plain cast, which is undefined behaviour when it does not fit
// (found by fuzz_session_manifest).
template <typename T>
T get(const json& j, const char* key, const fs::path& file) {
  if (!j.is_object() || !j.contains(key))
    throw FileFormatError(file, std::string("missing field '") + key + "'");
  const json& v = j.at(key);
  const auto wrong_type = [&] {
    return FileFormatError(file, std::string("field '") + key + "' has the wrong type");
  };
  if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) {
    if (!v.is_number_integer()) throw wrong_type();
    const bool fits = v.is_number_unsigned() ? std::in_range<T>(v.get<std::uint64_t>())
                                             : std::in_range<T>(v.get<std::int64_t>());
    if (!fits) throw FileFormatError(file, std::string("field '") + key + "' is out of range");
    return v.is_number_unsigned() ? static_cast<T>(v.get<std::uint64_t>())
                                  : static_cast<T>(v.get<std::int64_t>());
  } else {
    try {
      return v.get<T>();
    } catch (const json::exception&) {
      throw wrong_type();
    }
  }
}

drivers::CameraDescriptor camera_from_json(const json& j, const fs::path& file) {
  drivers::CameraDescriptor c;
  c.path = get<std::string>(j, "path", file);
  c.card = get<std::string>(j, "card", file);
  c.driver = get<std::string>(j, "driver", file);
  c.bus_info = get<std::string>(j, "bus_info", file);
  c.width = get<int>(j, "width", file);
  c.height = get<int>(j, "height", file);
  c.fps = get<double>(j, "fps", file);
  try {
    c.format = drivers::parse_pixel_format(get<std::string>(j, "format", file));
  } catch (const InvalidInputError& e) {
    throw FileFormatError(file, e.what());
  }
  if (c.width <= 0 || c.height <= 0 || c.width > 16384 || c.height > 16384)
    throw FileFormatError(file, "camera size is impossible");
  return c;
}

StepRecord step_from_json(const json& j, const SessionHeader& h, const fs::path& file) {
  StepRecord s;
  const auto index = get<std::int64_t>(j, "step", file);
  if (index < 0 || static_cast<std::size_t>(index) >= h.step_count)
    throw FileFormatError(file, "step index " + std::to_string(index) + " out of range");
  s.index = static_cast<std::size_t>(index);
  s.angle_rad = get<double>(j, "angle_rad", file);
  if (!std::isfinite(s.angle_rad)) throw FileFormatError(file, "angle is not finite");
  const json frames = get<json>(j, "frames", file);
  if (!frames.is_array() || frames.size() != static_cast<std::size_t>(h.laser_count) + 1)
    throw FileFormatError(file, "step " + std::to_string(index) + " must have " +
                                    std::to_string(h.laser_count + 1) + " frames");
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const json& f = frames[k];
    FrameRecord r;
    r.lasers = get<unsigned>(f, "lasers", file);
    const unsigned expected = k == 0 ? 0u : 1u << (k - 1);
    if (r.lasers != expected)
      throw FileFormatError(file, "step " + std::to_string(index) + " frame " + std::to_string(k) +
                                      " has the wrong laser state");
    r.file = get<std::string>(f, "file", file);
    if (r.file != frame_file_name(s.index, k, h.storage))
      throw FileFormatError(file, "step " + std::to_string(index) + " names frame file '" +
                                      r.file.substr(0, 64) + "'");
    r.rgb_crc32 = get<std::uint32_t>(f, "rgb_crc32", file);
    if (f.contains("capture")) {
      const json& c = f.at("capture");
      r.sequence = get<std::uint32_t>(c, "sequence", file);
      r.timestamp_s = get<double>(c, "timestamp_s", file);
      r.dropped_before = get<std::uint32_t>(c, "dropped_before", file);
    }
    s.frames.push_back(std::move(r));
  }
  return s;
}

CalibrationSessionInfo calibration_from_json(const json& j, const fs::path& file) {
  CalibrationSessionInfo c;
  const json pat = get<json>(j, "pattern", file);
  if (get<std::string>(pat, "type", file) != "chessboard")
    throw FileFormatError(file, "calibration pattern type must be chessboard");
  c.pattern.corner_cols = get<int>(pat, "corner_cols", file);
  c.pattern.corner_rows = get<int>(pat, "corner_rows", file);
  c.pattern.square_mm = get<double>(pat, "square_mm", file);
  c.pattern.bottom_mm = get<double>(pat, "bottom_mm", file);
  if (c.pattern.corner_cols < 3 || c.pattern.corner_rows < 3 || c.pattern.corner_cols > 100 ||
      c.pattern.corner_rows > 100)
    throw FileFormatError(file, "calibration pattern needs 3..100 inner corners each way");
  if (!(c.pattern.square_mm > 0 && c.pattern.square_mm < 1000) ||
      !(std::abs(c.pattern.bottom_mm) < 1000))
    throw FileFormatError(file, "calibration pattern square_mm or bottom_mm is impossible");
  const json poses = get<json>(j, "poses", file);
  if (!poses.is_array() || poses.empty() || poses.size() > kMaxSteps)
    throw FileFormatError(file, "calibration poses must be a non-empty list");
  for (const json& p : poses) {
    CalibrationSessionInfo::Pose pose;
    const std::string placement = get<std::string>(p, "placement", file);
    if (placement != "platter" && placement != "handheld")
      throw FileFormatError(file, "calibration pose placement must be platter or handheld");
    pose.on_platter = placement == "platter";
    pose.description = get<std::string>(p, "description", file);
    const json angles = get<json>(p, "angles_rad", file);
    if (!angles.is_array() || angles.empty() || angles.size() > kMaxSteps)
      throw FileFormatError(file, "a calibration pose needs a non-empty angles_rad list");
    for (const json& a : angles) {
      if (!a.is_number()) throw FileFormatError(file, "calibration angles must be numbers");
      const double v = a.get<double>();
      if (!std::isfinite(v) || std::abs(v) > 100.0)
        throw FileFormatError(file, "calibration angle is not finite or beyond +-100 rad");
      pose.angles_rad.push_back(v);
    }
    c.poses.push_back(std::move(pose));
  }
  return c;
}

}  // namespace

std::size_t CalibrationSessionInfo::step_count() const {
  std::size_t n = 0;
  for (const auto& p : poses) n += p.angles_rad.size();
  return n;
}

std::pair<std::size_t, double> CalibrationSessionInfo::step(std::size_t i) const {
  for (std::size_t k = 0; k < poses.size(); ++k) {
    if (i < poses[k].angles_rad.size()) return {k, poses[k].angles_rad[i]};
    i -= poses[k].angles_rad.size();
  }
  throw InvalidInputError("calibration session: no such step");
}

std::size_t CalibrationSessionInfo::first_step(std::size_t pose) const {
  std::size_t n = 0;
  for (std::size_t k = 0; k < pose && k < poses.size(); ++k) n += poses[k].angles_rad.size();
  return n;
}

double SessionHeader::step_angle(std::size_t i) const {
  if (calibration) return calibration->step(i).second;
  return start_angle_rad +
         2.0 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(step_count);
}

std::string header_to_json(const SessionHeader& h) {
  json j;
  j["format"] = kFormatName;
  j["version"] = h.version;
  j["step_count"] = h.step_count;
  j["laser_count"] = h.laser_count;
  j["frame_storage"] = storage_name(h.storage);
  j["start_angle_rad"] = h.start_angle_rad;
  j["settle_s"] = h.settle_s;
  j["discard_frames"] = h.discard_frames;
  j["camera"] = {{"path", h.camera.path},
                 {"card", h.camera.card},
                 {"driver", h.camera.driver},
                 {"bus_info", h.camera.bus_info},
                 {"width", h.camera.width},
                 {"height", h.camera.height},
                 {"format", drivers::to_string(h.camera.format)},
                 {"fps", h.camera.fps}};
  j["board"] = {
      {"device", h.board_device}, {"dialect", h.board_dialect}, {"firmware", h.board_firmware}};
  j["simulated"] = h.simulated;
  j["notes"] = h.notes;
  if (h.calibration) {
    const CalibrationSessionInfo& c = *h.calibration;
    j["kind"] = "calibration";
    json poses = json::array();
    for (const auto& p : c.poses)
      poses.push_back({{"placement", p.on_platter ? "platter" : "handheld"},
                       {"description", p.description},
                       {"angles_rad", p.angles_rad}});
    j["calibration"] = {{"pattern",
                         {{"type", "chessboard"},
                          {"corner_cols", c.pattern.corner_cols},
                          {"corner_rows", c.pattern.corner_rows},
                          {"square_mm", c.pattern.square_mm},
                          {"bottom_mm", c.pattern.bottom_mm}}},
                        {"poses", poses}};
  }
  return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

std::string step_to_json_line(const StepRecord& s) {
  json frames = json::array();
  for (const auto& f : s.frames)
    frames.push_back({{"lasers", f.lasers},
                      {"file", f.file},
                      {"rgb_crc32", f.rgb_crc32},
                      {"capture",
                       {{"sequence", f.sequence},
                        {"timestamp_s", f.timestamp_s},
                        {"dropped_before", f.dropped_before}}}});
  json j = {{"step", s.index}, {"angle_rad", s.angle_rad}, {"frames", frames}};
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

SessionManifest parse_session_manifest(std::string_view header_json, std::string_view steps_jsonl,
                                       const fs::path& folder) {
  const fs::path header_file = folder / "session.json";
  const fs::path steps_file = folder / "steps.jsonl";
  SessionManifest m;
  json h = json::parse(header_json, nullptr, false);
  if (h.is_discarded() || !h.is_object()) throw FileFormatError(header_file, "not a JSON object");
  if (get<std::string>(h, "format", header_file) != kFormatName)
    throw FileFormatError(header_file, "not a scanmesh session");
  SessionHeader& hd = m.header;
  hd.version = get<int>(h, "version", header_file);
  if (hd.version != 1)
    throw FileFormatError(header_file, "session version " + std::to_string(hd.version) +
                                           " is not supported (this build reads 1)");
  const auto steps = get<std::int64_t>(h, "step_count", header_file);
  if (steps < 1 || static_cast<std::uint64_t>(steps) > kMaxSteps)
    throw FileFormatError(header_file, "step_count must be 1.." + std::to_string(kMaxSteps));
  hd.step_count = static_cast<std::size_t>(steps);
  hd.laser_count = get<int>(h, "laser_count", header_file);
  if (hd.laser_count < 0 || hd.laser_count > kMaxLasers)
    throw FileFormatError(header_file, "laser_count must be 0..8");
  const auto storage = get<std::string>(h, "frame_storage", header_file);
  if (storage != "png" && storage != "mjpeg")
    throw FileFormatError(header_file, "frame_storage must be png or mjpeg");
  hd.storage = storage == "png" ? FrameStorage::Png : FrameStorage::Mjpeg;
  hd.start_angle_rad = get<double>(h, "start_angle_rad", header_file);
  hd.settle_s = get<double>(h, "settle_s", header_file);
  hd.discard_frames = get<int>(h, "discard_frames", header_file);
  hd.camera = camera_from_json(get<json>(h, "camera", header_file), header_file);
  const json board = get<json>(h, "board", header_file);
  hd.board_device = get<std::string>(board, "device", header_file);
  hd.board_dialect = get<std::string>(board, "dialect", header_file);
  hd.board_firmware = get<std::string>(board, "firmware", header_file);
  hd.simulated = get<bool>(h, "simulated", header_file);
  hd.notes = get<std::string>(h, "notes", header_file);
  // "kind" is absent in scan sessions (and in every session written before calibration
  // sessions existed).
  const std::string kind = h.contains("kind") ? get<std::string>(h, "kind", header_file) : "scan";
  if (kind == "calibration") {
    hd.calibration = calibration_from_json(get<json>(h, "calibration", header_file), header_file);
    if (hd.calibration->step_count() != hd.step_count)
      throw FileFormatError(header_file,
                            "step_count differs from the number of calibration pose angles");
  } else if (kind != "scan") {
    throw FileFormatError(header_file, "kind must be scan or calibration");
  }

  std::size_t pos = 0;
  while (pos < steps_jsonl.size()) {
    const std::size_t nl = steps_jsonl.find('\n', pos);
    if (nl == std::string_view::npos) break;  // torn last line: the step never completed
    const std::string_view line = steps_jsonl.substr(pos, nl - pos);
    const std::string where = "line " + std::to_string(m.steps.size() + 1);
    json j = json::parse(line, nullptr, false);
    if (j.is_discarded()) throw FileFormatError(steps_file, where + " is not JSON");
    StepRecord s = step_from_json(j, hd, steps_file);
    if (s.index != m.steps.size())
      throw FileFormatError(steps_file, where + " is step " + std::to_string(s.index) +
                                            ", expected " + std::to_string(m.steps.size()));
    m.steps.push_back(std::move(s));
    pos = nl + 1;
    m.complete_bytes = pos;
  }
  return m;
}

SessionManifest read_session_manifest(const fs::path& folder) {
  if (!fs::exists(folder / "session.json"))
    throw FileFormatError(folder, "not a session folder (no session.json)");
  const auto header = read_file_bytes(folder / "session.json");
  // A session is created with steps.jsonl before session.json, so one without it is damaged.
  if (!fs::exists(folder / "steps.jsonl"))
    throw FileFormatError(folder / "steps.jsonl",
                          "missing: the session's step journal is gone (damaged session)");
  const std::vector<std::uint8_t> steps = read_file_bytes(folder / "steps.jsonl");
  return parse_session_manifest(
      std::string_view(reinterpret_cast<const char*>(header.data()), header.size()),
      std::string_view(reinterpret_cast<const char*>(steps.data()), steps.size()), folder);
}

SessionWriter::SessionWriter(fs::path folder, SessionHeader header, std::size_t done)
    : folder_(std::move(folder)), header_(std::move(header)), steps_done_(done) {}

SessionWriter SessionWriter::create(const fs::path& folder, const SessionHeader& header) {
  if (header.calibration && header.calibration->step_count() != header.step_count)
    throw InvalidInputError("calibration session: step count differs from the poses' angles");
  if (header.step_count < 1 || header.step_count > kMaxSteps)
    throw InvalidInputError("step count must be 1.." + std::to_string(kMaxSteps));
  if (header.laser_count < 0 || header.laser_count > kMaxLasers)
    throw InvalidInputError("laser count must be 0..8");
  std::error_code ec;
  if (fs::exists(folder / "session.json"))
    throw InvalidInputError("'" + folder.string() +
                            "' already holds a session; continue it with --resume");
  fs::create_directories(folder / "frames", ec);
  if (ec) throw IoError("cannot create '" + (folder / "frames").string() + "': " + ec.message());
  // steps.jsonl first (empty), session.json last: a folder with session.json is a session.
  write_file_atomically(folder / "steps.jsonl", std::string_view());
  write_file_atomically(folder / "session.json", header_to_json(header));
  fsync_path(folder, true);
  // Round trip through the parser so what is recorded is what a reader will see.
  return SessionWriter(folder, read_session_manifest(folder).header, 0);
}

SessionWriter SessionWriter::resume(const fs::path& folder) {
  SessionManifest m = read_session_manifest(folder);
  const fs::path steps = folder / "steps.jsonl";
  std::error_code ec;
  if (fs::exists(steps) && fs::file_size(steps) != m.complete_bytes) {
    // A torn last line: the step it describes is captured again.
    fs::resize_file(steps, m.complete_bytes, ec);
    if (ec) throw IoError("cannot truncate '" + steps.string() + "': " + ec.message());
    fsync_path(steps, false);
  }
  // Orphan frames of the interrupted step and temporary files of an interrupted write.
  for (const auto& entry : fs::directory_iterator(folder / "frames", ec)) {
    const std::string name = entry.path().filename().string();
    const bool temp = name.starts_with(".");
    std::size_t step = 0;
    const bool numbered = std::sscanf(name.c_str(), "%zu_", &step) == 1;
    if (temp || (numbered && step >= m.steps.size())) fs::remove(entry.path(), ec);
  }
  return SessionWriter(folder, m.header, m.steps.size());
}

void SessionWriter::rewind(std::size_t steps) {
  if (steps >= steps_done_) return;
  const fs::path file = folder_ / "steps.jsonl";
  const auto bytes = read_file_bytes(file);
  std::size_t pos = 0;
  for (std::size_t n = 0; n < steps; ++n) {
    const auto it = std::find(bytes.begin() + static_cast<std::ptrdiff_t>(pos), bytes.end(),
                              std::uint8_t('\n'));
    if (it == bytes.end()) throw FileFormatError(file, "fewer lines than recorded steps");
    pos = static_cast<std::size_t>(it - bytes.begin()) + 1;
  }
  write_file_atomically(file, std::span<const std::uint8_t>(bytes.data(), pos));
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder_ / "frames", ec)) {
    std::size_t step = 0;
    if (std::sscanf(entry.path().filename().string().c_str(), "%zu_", &step) == 1 && step >= steps)
      fs::remove(entry.path(), ec);
  }
  fsync_path(folder_ / "frames", true);
  steps_done_ = steps;
}

void SessionWriter::append_step(double angle_rad, const std::vector<drivers::Frame>& frames) {
  if (complete()) throw InvalidInputError("the session already has all its steps");
  if (frames.size() != static_cast<std::size_t>(header_.laser_count) + 1)
    throw InvalidInputError("a step needs " + std::to_string(header_.laser_count + 1) + " frames");
  StepRecord record;
  record.index = steps_done_;
  record.angle_rad = angle_rad;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const drivers::Frame& f = frames[k];
    if (f.rgb.width != header_.camera.width || f.rgb.height != header_.camera.height)
      throw InvalidInputError("frame size differs from the session's camera size");
    FrameRecord r;
    r.lasers = k == 0 ? 0u : 1u << (k - 1);
    r.file = frame_file_name(record.index, k, header_.storage);
    r.rgb_crc32 = pixels_crc(f.rgb);
    r.sequence = f.sequence;
    r.timestamp_s = f.timestamp_s;
    r.dropped_before = f.dropped_before;
    const fs::path path = folder_ / r.file;
    if (header_.storage == FrameStorage::Mjpeg) {
      if (f.original.empty())
        throw InvalidInputError("MJPEG storage needs the camera's MJPEG bytes");
      write_file_atomically(path, std::span<const std::uint8_t>(f.original));
    } else {
      write_png(path, f.rgb);
    }
    record.frames.push_back(std::move(r));
  }
  fsync_path(folder_ / "frames", true);
  const std::string line = step_to_json_line(record);
  const fs::path steps = folder_ / "steps.jsonl";
  // non-atomic: the append-only step journal; a torn last line is dropped on resume.
  const int flags = O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC;  // non-atomic: step journal
  const int fd = ::open(steps.c_str(), flags, 0644);
  if (fd < 0) throw IoError("cannot open '" + steps.string() + "': " + std::strerror(errno));
  // A write that fails midway (disk full) is cut back to the journal's length before it, so
  // the journal never holds a torn line it did not need to (a kill -9 still can; resume
  // drops it) and the steps recorded so far stay readable as they are.
  struct stat before {};
  const off_t old_size = ::fstat(fd, &before) == 0 ? before.st_size : -1;
  std::size_t done = 0;
  while (done < line.size()) {
    const ssize_t n = ::write(fd, line.data() + done, line.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int e = n == 0 ? EIO : errno;
      if (old_size >= 0 && ::ftruncate(fd, old_size) == 0) ::fsync(fd);
      ::close(fd);
      throw IoError("cannot append to '" + steps.string() + "': " + std::strerror(e) +
                    "; the steps recorded so far are kept: free space and continue with "
                    "--resume");
    }
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) {
    const int e = errno;
    ::close(fd);
    throw IoError("cannot fsync '" + steps.string() + "': " + std::strerror(e));
  }
  ::close(fd);
  ++steps_done_;
}

SessionReader::SessionReader(const fs::path& folder)
    : folder_(folder), manifest_(read_session_manifest(folder)) {}

Image8 SessionReader::frame(std::size_t step, std::size_t k) const {
  if (step >= manifest_.steps.size() || k >= manifest_.steps[step].frames.size())
    throw InvalidInputError("no frame " + std::to_string(k) + " in step " + std::to_string(step));
  const FrameRecord& r = manifest_.steps[step].frames[k];
  const fs::path path = folder_ / r.file;
  std::error_code ec;
  if (fs::is_symlink(path, ec))
    throw FileFormatError(path, "is a symbolic link; a session's frames are its own files");
  // Part of the session is gone: the session is damaged (exit 4), not an OS failure.
  if (!fs::exists(path, ec)) throw FileFormatError(path, "recorded frame is missing");
  Image8 img;
  if (manifest_.header.storage == FrameStorage::Png) {
    img = read_png(path);
  } else {
    const auto bytes = read_file_bytes(path);
    img = drivers::decode_frame(drivers::PixelFormat::Mjpeg, bytes, manifest_.header.camera.width,
                                manifest_.header.camera.height, 0, path.string());
  }
  if (img.width != manifest_.header.camera.width || img.height != manifest_.header.camera.height ||
      img.channels != 3)
    throw FileFormatError(path, "frame size or channels differ from session.json");
  if (pixels_crc(img) != r.rgb_crc32)
    throw FileFormatError(path, "frame content does not match its CRC in steps.jsonl");
  return img;
}

std::optional<SessionReader::Damage> SessionReader::first_damaged_step() const {
  for (std::size_t i = 0; i < manifest_.steps.size(); ++i)
    for (std::size_t k = 0; k < manifest_.steps[i].frames.size(); ++k) {
      try {
        (void)frame(i, k);
      } catch (const Error& e) {  // FileFormatError, IoError (missing file)
        return Damage{i, e.what()};
      }
    }
  return std::nullopt;
}

ScanStep SessionReader::step(std::size_t i) const {
  if (i >= manifest_.steps.size())
    throw InvalidInputError("step " + std::to_string(i) + " is not in the session (" +
                            std::to_string(manifest_.steps.size()) + " recorded)");
  const StepRecord& r = manifest_.steps[i];
  ScanStep s;
  s.index = r.index;
  s.angle_rad = r.angle_rad;
  s.timestamp_s = r.frames.front().timestamp_s;
  s.laser_off = frame(i, 0);
  for (std::size_t k = 1; k < r.frames.size(); ++k) s.laser_on.push_back(frame(i, k));
  return s;
}

}  // namespace scanmesh
