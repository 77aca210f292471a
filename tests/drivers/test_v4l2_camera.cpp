// The real V4L2 backend against an emulated capture node (umockdev) answered by the simulated
// camera: QUERYCAP, ENUM_FMT, S_FMT, S_PARM, controls, USERPTR streaming, sequence gaps,
// corrupt MJPEG, EIO, unplug. MMAP is tested up to its boundary (docs/testing.md).
#include <gtest/gtest.h>

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <thread>
#include <iostream>

#include "board_test_support.h"
#include "scanmesh/drivers/camera.h"
#include "scanmesh/sim/emulated_devices.h"
#include "scanmesh/sim/sim_camera.h"

namespace scanmesh::drivers {
namespace {

using test::expect_device_error;

struct CameraRig {
  explicit CameraRig(sim::SimCameraOptions o = fast_camera()) {
    camera = std::make_shared<sim::SimCamera>(
        sim::synthetic_turntable_renderer(o.width, o.height), [this] { return angle.load(); },
        [this] { return lasers.load(); }, o);
    path = devices.add_camera(camera);
  }
  static sim::SimCameraOptions fast_camera() {
    sim::SimCameraOptions o;
    o.width = 64;
    o.height = 48;
    o.time_scale = 0.05;  // 30 fps -> a frame every 1.7 ms
    return o;
  }
  CameraSettings settings(PixelFormat f, IoMethod io = IoMethod::UserPtr) const {
    CameraSettings s;
    s.width = 64;
    s.height = 48;
    s.format = f;
    s.io = io;
    s.buffer_count = 3;
    s.timeout = std::chrono::milliseconds(5000);
    return s;
  }
  std::atomic<double> angle{0.3};
  std::atomic<unsigned> lasers{0};
  sim::EmulatedDevices devices;
  std::shared_ptr<sim::SimCamera> camera;
  std::string path;
};

TEST(V4l2Camera, ListsTheEmulatedCameraWithItsFormats) {
  CameraRig rig;
  const auto cams = list_cameras();
  ASSERT_EQ(cams.size(), 1u);
  EXPECT_EQ(cams[0].path, "/dev/video0");
  EXPECT_EQ(cams[0].card, "Simulated UVC Camera");
  EXPECT_EQ(cams[0].driver, "uvcvideo");
  EXPECT_EQ(cams[0].bus_info, "usb-scanmesh-sim-1");
  ASSERT_EQ(cams[0].formats.size(), 3u);
  EXPECT_EQ(cams[0].all_formats[0], "YUYV");
  EXPECT_EQ(cams[0].all_formats[1], "MJPG");
}

TEST(V4l2Camera, Rgb24FramesAreTheRendersBitForBit) {
  CameraRig rig;
  V4l2Camera cam("/dev/video0", rig.settings(PixelFormat::Rgb24));
  for (unsigned mask : {0u, 1u, 2u, 3u}) {
    rig.lasers = mask;
    rig.angle = 0.1 * (mask + 1);
    cam.flush();
    const Frame f = cam.grab();
    const Image8 truth = rig.camera->render(0.1 * (mask + 1), mask);
    ASSERT_EQ(f.rgb.width, 64);
    EXPECT_EQ(f.rgb.pixels, truth.pixels) << "laser mask " << mask;
  }
  EXPECT_EQ(cam.descriptor().card, "Simulated UVC Camera");
  EXPECT_EQ(cam.dropped_frames(), 0u);
}

TEST(V4l2Camera, OpensByCardName) {
  CameraRig rig;
  V4l2Camera cam("Simulated UVC Camera", rig.settings(PixelFormat::Yuyv));
  EXPECT_EQ(cam.descriptor().path, "/dev/video0");
}

TEST(V4l2Camera, YuyvDecodesCloseToTheRender) {
  CameraRig rig;
  V4l2Camera cam("/dev/video0", rig.settings(PixelFormat::Yuyv));
  rig.lasers = 1;
  const Frame f = cam.grab();
  const Image8 truth = rig.camera->render(0.3, 1);
  // YUYV shares chroma between pixel pairs: per-channel error stays small except at the laser
  // line's edges; the mean absolute error must be small.
  double sum = 0;
  for (std::size_t i = 0; i < truth.pixels.size(); ++i)
    sum += std::abs(int(f.rgb.pixels[i]) - int(truth.pixels[i]));
  EXPECT_LT(sum / truth.pixels.size(), 6.0);
  EXPECT_TRUE(f.original.empty());
}

TEST(V4l2Camera, MjpegKeepsTheOriginalBytes) {
  CameraRig rig;
  V4l2Camera cam("/dev/video0", rig.settings(PixelFormat::Mjpeg));
  const Frame f = cam.grab();
  ASSERT_GE(f.original.size(), 4u);
  EXPECT_EQ(f.original[0], 0xff);
  EXPECT_EQ(f.original[1], 0xd8);
  const Image8 again = decode_frame(PixelFormat::Mjpeg, f.original, 64, 48);
  EXPECT_EQ(again.pixels, f.rgb.pixels);
}

TEST(V4l2Camera, SequenceGapsAreCountedAsDrops) {
  auto o = CameraRig::fast_camera();
  o.faults.drop_sequences = {2, 3, 7};
  CameraRig rig(o);
  V4l2Camera cam("/dev/video0", rig.settings(PixelFormat::Rgb24));
  std::uint32_t dropped = 0, last = 0;
  for (int i = 0; i < 6; ++i) {
    const Frame f = cam.grab();
    dropped += f.dropped_before;
    last = f.sequence;
  }
  EXPECT_EQ(last, 8u);  // sequences 0 1 4 5 6 8
  EXPECT_EQ(dropped, 3u);
  EXPECT_EQ(cam.dropped_frames(), 3u);
}

TEST(V4l2Camera, OneCorruptMjpegFrameIsDroppedARunIsAnError) {
  auto o = CameraRig::fast_camera();
  o.faults.corrupt_sequences = {1};
  CameraRig rig(o);
  V4l2Camera cam("/dev/video0", rig.settings(PixelFormat::Mjpeg));
  EXPECT_EQ(cam.grab().sequence, 0u);
  const Frame f = cam.grab();
  EXPECT_EQ(f.sequence, 2u);
  EXPECT_EQ(f.dropped_before, 1u);
  rig.camera->set_faults({.corrupt_sequences = {3, 4, 5, 6}});
  expect_device_error([&] { cam.grab(); }, "/dev/video0", "corrupt frames in a row");
}

TEST(V4l2Camera, EioAndUnplugAreDeviceErrors) {
  auto o = CameraRig::fast_camera();
  o.faults.eio_at_sequence = 1;
  CameraRig rig(o);
  V4l2Camera cam("/dev/video0", rig.settings(PixelFormat::Rgb24));
  cam.grab();
  expect_device_error([&] { cam.grab(); }, "/dev/video0", "I/O error (EIO)");
  rig.camera->set_faults({.unplug_at_sequence = 0});
  expect_device_error([&] { cam.grab(); }, "/dev/video0", "unplugged");
}

TEST(V4l2Camera, UnsupportedFormatIsADeviceError) {
  auto o = CameraRig::fast_camera();
  o.formats = {sim::SimPixelFormat::Yuyv};
  CameraRig rig(o);
  expect_device_error([&] { V4l2Camera cam("/dev/video0", rig.settings(PixelFormat::Mjpeg)); },
                      "/dev/video0", "unsupported format mjpeg (the camera offers YUYV)");
}

TEST(V4l2Camera, BusyCameraIsADeviceError) {
  auto o = CameraRig::fast_camera();
  o.faults.busy = true;
  CameraRig rig(o);
  expect_device_error([&] { V4l2Camera cam("/dev/video0", rig.settings(PixelFormat::Yuyv)); },
                      "/dev/video0", "VIDIOC_S_FMT: busy (another program streams from it)");
}

TEST(V4l2Camera, ControlsReachTheDevice) {
  CameraRig rig;
  auto s = rig.settings(PixelFormat::Yuyv);
  s.exposure = 120;
  s.gain = 7;
  s.brightness = 3;
  V4l2Camera cam("/dev/video0", s);
  EXPECT_EQ(rig.devices.camera_control(V4L2_CID_EXPOSURE_AUTO), V4L2_EXPOSURE_MANUAL);
  EXPECT_EQ(rig.devices.camera_control(V4L2_CID_EXPOSURE_ABSOLUTE), 120);
  EXPECT_EQ(rig.devices.camera_control(V4L2_CID_GAIN), 7);
  EXPECT_EQ(rig.devices.camera_control(V4L2_CID_BRIGHTNESS), 3);
  EXPECT_EQ(cam.grab().rgb.width, 64);
}

// The live view's exposure slider: the control changes while the camera streams.
TEST(V4l2Camera, ExposureChangesWhileStreaming) {
  CameraRig rig;
  V4l2Camera cam("/dev/video0", rig.settings(PixelFormat::Rgb24));
  EXPECT_EQ(cam.grab().rgb.width, 64);
  cam.set_exposure(300);
  EXPECT_EQ(rig.devices.camera_control(V4L2_CID_EXPOSURE_AUTO), V4L2_EXPOSURE_MANUAL);
  EXPECT_EQ(rig.devices.camera_control(V4L2_CID_EXPOSURE_ABSOLUTE), 300);
  EXPECT_EQ(cam.grab().rgb.width, 64);
}

// The simulated sensor collects light in proportion to its exposure and clips at 255.
TEST(SimCamera, ExposureGainScalesAndClipsThePixels) {
  CameraRig rig;
  rig.lasers = 1;  // the laser line is bright enough to clip at twice the exposure
  const Image8 nominal = rig.camera->render(0.3, 1);
  rig.camera->set_exposure_gain(2.0);
  rig.camera->start_streaming();
  sim::SimCamera::Capture c;
  for (int i = 0; i < 20000 && c.status != sim::SimCamera::Capture::Status::Ok; ++i) {
    c = rig.camera->capture(sim::SimPixelFormat::Rgb24);
    if (c.status != sim::SimCamera::Capture::Status::Ok)
      std::this_thread::sleep_for(std::chrono::microseconds(100));
  }
  ASSERT_EQ(c.status, sim::SimCamera::Capture::Status::Ok);
  EXPECT_EQ(rig.camera->frames_delivered(), 1u);
  ASSERT_EQ(c.bytes.size(), nominal.pixels.size());
  int clipped = 0;
  for (std::size_t i = 0; i < c.bytes.size(); ++i) {
    EXPECT_EQ(c.bytes[i], std::min(255, 2 * nominal.pixels[i])) << "byte " << i;
    clipped += 2 * nominal.pixels[i] > 255;
  }
  EXPECT_GT(clipped, 0);
  EXPECT_THROW(rig.camera->set_exposure_gain(0), std::invalid_argument);
  EXPECT_THROW(rig.camera->set_exposure_gain(1e9), std::invalid_argument);
}

TEST(V4l2Camera, WithoutSettingsNoControlIsTouched) {
  CameraRig rig;
  V4l2Camera cam("/dev/video0", rig.settings(PixelFormat::Yuyv));
  EXPECT_FALSE(rig.devices.camera_control(V4L2_CID_EXPOSURE_AUTO).has_value());
  EXPECT_FALSE(rig.devices.camera_control(V4L2_CID_GAIN).has_value());
}

// The boundary of emulation (docs/testing.md): MMAP buffers are requested and queried through
// the real code, and mmap() of the emulated node fails with a clear DeviceError.
TEST(V4l2Camera, MmapStopsAtTheEmulationBoundaryWithAClearError) {
  CameraRig rig;
  const std::string message = expect_device_error(
      [&] { V4l2Camera cam("/dev/video0", rig.settings(PixelFormat::Yuyv, IoMethod::Mmap)); },
      "/dev/video0", "mmap of buffer 0: the node does not support memory mapping");
  EXPECT_FALSE(message.empty());
  std::cout << "MMAP boundary: " << message << "\n";
}

// The other boundary: poll() on an emulated node never reports POLLIN (it is a socket to
// umockdev's thread), which is why grab() polls in slices and dequeues without blocking.
TEST(V4l2Camera, PollOnTheEmulatedNodeDoesNotSignalFrames) {
  CameraRig rig;
  V4l2Camera cam("/dev/video0", rig.settings(PixelFormat::Rgb24));
  cam.grab();
  const int fd = ::open("/dev/video0", O_RDWR | O_NONBLOCK);
  ASSERT_GE(fd, 0);
  pollfd p{fd, POLLIN, 0};
  EXPECT_EQ(::poll(&p, 1, 30), 0);
  ::close(fd);
}

}  // namespace
}  // namespace scanmesh::drivers
