// Session identity as the tests define it: the same step records (index, angle, laser states,
// frame files, frame CRCs) and byte-identical frame files. Capture details (frame sequence
// numbers, timestamps) are measurements and differ between two captures of the same scan.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>

#include "scanmesh/acquisition/session.h"
#include "scanmesh/core/atomic_file.h"

namespace scanmesh::test {

inline ::testing::AssertionResult sessions_identical(const std::filesystem::path& a,
                                                     const std::filesystem::path& b) {
  const SessionManifest ma = read_session_manifest(a), mb = read_session_manifest(b);
  if (ma.steps.size() != mb.steps.size())
    return ::testing::AssertionFailure()
           << "step counts " << ma.steps.size() << " vs " << mb.steps.size();
  for (std::size_t i = 0; i < ma.steps.size(); ++i) {
    const StepRecord &sa = ma.steps[i], &sb = mb.steps[i];
    if (sa.index != sb.index || sa.angle_rad != sb.angle_rad ||
        sa.frames.size() != sb.frames.size())
      return ::testing::AssertionFailure() << "step " << i << " records differ";
    for (std::size_t k = 0; k < sa.frames.size(); ++k) {
      const FrameRecord &fa = sa.frames[k], &fb = sb.frames[k];
      if (fa.lasers != fb.lasers || fa.file != fb.file || fa.rgb_crc32 != fb.rgb_crc32)
        return ::testing::AssertionFailure() << "step " << i << " frame " << k << " differs";
      if (read_file_bytes(a / fa.file) != read_file_bytes(b / fb.file))
        return ::testing::AssertionFailure() << "file " << fa.file << " differs";
    }
  }
  return ::testing::AssertionSuccess();
}

}  // namespace scanmesh::test
