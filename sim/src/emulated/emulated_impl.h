// Private state of EmulatedDevices shared by the USB and V4L2 halves.
#pragma once

#include <umockdev.h>

#include <chrono>
#include <deque>
#include <list>
#include <mutex>
#include <vector>

#include "scanmesh/sim/emulated_devices.h"

namespace scanmesh::sim {

enum class EmulatedBridge { CdcAcm, Ch34x, Ftdi };

struct UsbBoardEmulation {
  std::shared_ptr<SimBoardFirmware> firmware;
  EmulatedBridge bridge = EmulatedBridge::CdcAcm;
  unsigned char ep_in = 0x83, ep_out = 0x04;
  int in_packet = 64;
  std::chrono::steady_clock::time_point last_in_packet{};
  UMockdevIoctlBase* handler = nullptr;
  std::mutex mutex;
  EmulatedUsbBoardState state;
  std::vector<UMockdevIoctlData*> done;     //!< completed URBs waiting to be reaped
  std::list<UMockdevIoctlData*> in_flight;  //!< bulk IN URBs waiting for firmware output
  std::string unread;                       //!< firmware output not yet placed in a URB
};

struct CameraEmulation;

struct EmulatedDevices::Impl {
  UMockdevTestbed* testbed = nullptr;
  std::vector<std::unique_ptr<UsbBoardEmulation>> boards;
  std::vector<CameraEmulation*> cameras;  // owned; freed by destroy_camera_emulation
  ~Impl();
};

//! Defined in emulated_v4l2.cpp.
void destroy_camera_emulation(CameraEmulation* camera);

}  // namespace scanmesh::sim
