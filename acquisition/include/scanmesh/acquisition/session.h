// Recorded scan sessions: an append-only folder that a capture writes step by step and a replay
// reads back as a ScanStepSource (docs/formats.md, "Scan session folder").
//
//   SESSION/session.json   header, written once (atomically) when the session is created
//   SESSION/steps.jsonl    one JSON line per complete step, appended and fsync'd
//   SESSION/frames/        one file per frame: lossless PNG, or the camera's MJPEG bytes (.jpg)
//
// A step's frames are written (temp file + fsync + rename) before its line is appended, so a
// line in steps.jsonl always refers to complete frames; a kill can at most leave a torn last
// line and orphan frames of the step in progress, which a resume discards and rewrites.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "scanmesh/acquisition/scan_step.h"
#include "scanmesh/drivers/camera.h"

namespace scanmesh {

enum class FrameStorage { Png, Mjpeg };

//! What a calibration session (`scanmesh scan --calibration`) records besides the frames: the
//! printed pattern, so `scanmesh calibrate SESSION` needs no other input, and the board poses.
//! Each pose is one placement of the board: standing on the platter (the table turns through the
//! pose's angles, one step each) or held in front of the camera (the table stands still).
struct CalibrationSessionInfo {
  struct Pattern {
    int corner_cols = 11, corner_rows = 6;  //!< inner corners
    double square_mm = 13.0;
    double bottom_mm = 25.0;  //!< lowest corner row to the board's bottom edge (along the board)
  } pattern;
  struct Pose {
    bool on_platter = true;
    std::string description;         //!< what the user was asked to do
    std::vector<double> angles_rad;  //!< one step per angle
  };
  std::vector<Pose> poses;

  std::size_t step_count() const;
  //! The pose and the angle of step i (throws InvalidInputError past the end).
  std::pair<std::size_t, double> step(std::size_t i) const;
  //! First step of pose k.
  std::size_t first_step(std::size_t pose) const;
};

//! session.json.
struct SessionHeader {
  int version = 1;
  std::size_t step_count = 0;
  int laser_count = 0;
  FrameStorage storage = FrameStorage::Png;
  double start_angle_rad = 0;
  double settle_s = 0;
  int discard_frames = 0;
  drivers::CameraDescriptor camera;
  std::string board_device, board_dialect, board_firmware;
  bool simulated = false;
  std::string notes;  //!< free text (e.g. the simulation settings)
  //! Set for a calibration session (session.json "kind": "calibration"); step_count is then the
  //! sum of the poses' angles.
  std::optional<CalibrationSessionInfo> calibration;

  //! Angle of step i: start + i * 2 pi / step_count; a calibration session's plan angle.
  double step_angle(std::size_t i) const;
};

//! One frame of a step as recorded.
struct FrameRecord {
  unsigned lasers = 0;          //!< bit mask of the lasers that were on
  std::string file;             //!< relative to the session folder
  std::uint32_t rgb_crc32 = 0;  //!< CRC-32 of the decoded RGB pixels
  // Capture details (differ between two captures of the same scene; not part of identity):
  std::uint32_t sequence = 0;
  double timestamp_s = 0;
  std::uint32_t dropped_before = 0;
};

//! One line of steps.jsonl.
struct StepRecord {
  std::size_t index = 0;
  double angle_rad = 0;
  std::vector<FrameRecord> frames;  //!< [0]: lasers off, [1 + k]: laser k on
};

struct SessionManifest {
  SessionHeader header;
  std::vector<StepRecord> steps;
  //! Bytes of steps.jsonl that hold complete lines (a torn last line is not counted).
  std::size_t complete_bytes = 0;
};

//! Parses session.json and steps.jsonl. A torn last line of steps.jsonl (no newline) is ignored;
//! anything else malformed throws FileFormatError naming `folder`'s file. Pure, for fuzzing
//! (tests/fuzz/fuzz_session_manifest.cpp).
SessionManifest parse_session_manifest(std::string_view header_json, std::string_view steps_jsonl,
                                       const std::filesystem::path& folder = "session");
std::string header_to_json(const SessionHeader& header);
std::string step_to_json_line(const StepRecord& step);

//! Reads a session folder's manifest (no frames). Throws FileFormatError / IoError.
SessionManifest read_session_manifest(const std::filesystem::path& folder);

//! Appends steps to a session folder.
class SessionWriter {
 public:
  //! Creates a new session; the folder must not exist or be empty.
  static SessionWriter create(const std::filesystem::path& folder, const SessionHeader& header);
  //! Opens an existing session to continue it: drops a torn last line and orphan frames.
  static SessionWriter resume(const std::filesystem::path& folder);

  const SessionHeader& header() const { return header_; }
  std::size_t steps_done() const { return steps_done_; }
  bool complete() const { return steps_done_ >= header_.step_count; }

  //! Drops every step from `steps` on (the journal is rewritten atomically, their frames
  //! deleted): a calibration resume restarts the interrupted board pose, because the board may
  //! have moved. Throws IoError.
  void rewind(std::size_t steps);

  //! Writes the frames of the next step and appends its record (fsync'd). `frames[0]` is the
  //! laser-off frame, `frames[1 + k]` laser k. Throws IoError.
  void append_step(double angle_rad, const std::vector<drivers::Frame>& frames);

 private:
  SessionWriter(std::filesystem::path folder, SessionHeader header, std::size_t done);
  std::filesystem::path folder_;
  SessionHeader header_;
  std::size_t steps_done_ = 0;
};

//! Replay: a recorded session as a ScanStepSource. Deterministic; verifies each frame's CRC.
class SessionReader final : public ScanStepSource {
 public:
  explicit SessionReader(const std::filesystem::path& folder);
  std::size_t step_count() const override { return manifest_.steps.size(); }
  int laser_count() const override { return manifest_.header.laser_count; }
  ScanStep step(std::size_t i) const override;
  const SessionManifest& manifest() const { return manifest_; }
  bool complete() const { return manifest_.steps.size() == manifest_.header.step_count; }
  //! Reads one frame and checks its CRC. Throws FileFormatError on a damaged frame (also one
  //! that is a symbolic link: a session's frames are its own files).
  Image8 frame(std::size_t step, std::size_t k) const;

  struct Damage {
    std::size_t step;    //!< the first step with a missing, unreadable or wrong frame
    std::string reason;  //!< what is wrong, naming the file
  };
  //! Reads every recorded frame (size, decoding, CRC): the first damaged step, if any. Before a
  //! resume, so that a damaged recording is re-captured instead of found by the replay.
  std::optional<Damage> first_damaged_step() const;

 private:
  std::filesystem::path folder_;
  SessionManifest manifest_;
};

}  // namespace scanmesh
