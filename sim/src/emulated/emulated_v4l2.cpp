#include "emulated_impl.h"

namespace scanmesh::sim {
struct CameraEmulation {};
void destroy_camera_emulation(CameraEmulation* camera) { delete camera; }
std::string EmulatedDevices::add_camera(std::shared_ptr<SimCamera>, int) {
  throw std::runtime_error("not yet");
}
}  // namespace scanmesh::sim
