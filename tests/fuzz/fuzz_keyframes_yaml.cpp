// Fuzz target: the animated skeleton (keyframe) YAML reader, AnimatedSkeleton::from_yaml_text and
// is_animated_yaml (sim/animated_skeleton.h); an accepted animation is evaluated at its start,
// middle and end.
#include <cstddef>
#include <cstdint>

#include "fuzz_support.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/sim/animated_skeleton.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using scanmesh::sim::AnimatedSkeleton;
  const std::string text = scanmesh::fuzz::as_text(data, size);
  (void)AnimatedSkeleton::is_animated_yaml(text);
  try {
    const AnimatedSkeleton s = AnimatedSkeleton::from_yaml_text(text, "fuzz.yaml");
    for (double t : {s.start_time(), 0.5 * (s.start_time() + s.end_time()), s.end_time()})
      (void)s.elements_at(t);
  } catch (const scanmesh::Error&) {
  }
  return 0;
}
