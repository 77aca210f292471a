// V4L2 emulation: the ioctls of a UVC capture node answered by the simulated camera. Streaming
// works with USERPTR buffers (the frame is written into the client's buffer through
// UMockdevIoctlData at DQBUF time). MMAP buffers can be requested and queried, but mmap() of the
// emulated node fails: it is a unix socket, which cannot be mapped (docs/testing.md).
#include <linux/videodev2.h>
#include <sys/ioctl.h>

#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <deque>
#include <map>
#include <stdexcept>

#include "emulated_impl.h"
#include "scanmesh/sim/sim_camera.h"

namespace scanmesh::sim {

struct CameraEmulation {
  std::shared_ptr<SimCamera> camera;
  UMockdevIoctlBase* handler = nullptr;
  std::mutex mutex;
  SimPixelFormat format = SimPixelFormat::Yuyv;
  unsigned memory = 0;
  struct Slot {
    bool queued = false;
    unsigned long userptr = 0;
    std::uint32_t length = 0;
  };
  std::vector<Slot> slots;
  std::deque<unsigned> queue;  //!< indices in the order they were queued
  bool streaming = false;
  std::map<std::uint32_t, std::int32_t> controls;
  std::uint32_t fps_numerator = 1, fps_denominator = 30;
};

void destroy_camera_emulation(CameraEmulation* camera) {
  if (!camera) return;
  if (camera->handler) g_object_unref(camera->handler);
  delete camera;
}

namespace {

std::uint32_t to_fourcc(SimPixelFormat f) {
  switch (f) {
    case SimPixelFormat::Yuyv:
      return V4L2_PIX_FMT_YUYV;
    case SimPixelFormat::Mjpeg:
      return V4L2_PIX_FMT_MJPEG;
    case SimPixelFormat::Rgb24:
      return V4L2_PIX_FMT_RGB24;
  }
  return 0;
}

void fill_pix(const CameraEmulation& cam, v4l2_pix_format& pix) {
  const auto& o = cam.camera->options();
  pix.width = static_cast<std::uint32_t>(o.width);
  pix.height = static_cast<std::uint32_t>(o.height);
  pix.pixelformat = to_fourcc(cam.format);
  pix.field = V4L2_FIELD_NONE;
  pix.colorspace = V4L2_COLORSPACE_SRGB;
  switch (cam.format) {
    case SimPixelFormat::Yuyv:
      pix.bytesperline = pix.width * 2;
      pix.sizeimage = pix.bytesperline * pix.height;
      break;
    case SimPixelFormat::Rgb24:
      pix.bytesperline = pix.width * 3;
      pix.sizeimage = pix.bytesperline * pix.height;
      break;
    case SimPixelFormat::Mjpeg:
      pix.bytesperline = 0;
      pix.sizeimage = pix.width * pix.height * 3 + 4096;  // worst case, as uvcvideo reports
      break;
  }
}

template <typename T>
T* view(UMockdevIoctlData* d) {
  return reinterpret_cast<T*>(d->data);
}

// Completes the client's ioctl with `result` and `error` (its errno); TRUE tells umockdev the
// request was handled here.
gboolean complete_ioctl(UMockdevIoctlClient* client, long result, int error) {
  umockdev_ioctl_client_complete(client, result, error);
  return TRUE;
}

// The ioctl's argument struct, copied from the client; umockdev writes it back on completion.
UMockdevIoctlData* resolve_arg(UMockdevIoctlData* arg, std::size_t size) {
  return umockdev_ioctl_data_resolve(arg, 0, size, nullptr);
}

gboolean answer_querycap(const CameraEmulation& cam, UMockdevIoctlClient* client,
                         UMockdevIoctlData* arg) {
  const auto& options = cam.camera->options();
  UMockdevIoctlData* d = resolve_arg(arg, sizeof(v4l2_capability));
  auto* cap = view<v4l2_capability>(d);
  std::memset(cap, 0, sizeof *cap);
  std::snprintf(reinterpret_cast<char*>(cap->driver), sizeof cap->driver, "uvcvideo");
  std::snprintf(reinterpret_cast<char*>(cap->card), sizeof cap->card, "%s", options.card.c_str());
  std::snprintf(reinterpret_cast<char*>(cap->bus_info), sizeof cap->bus_info, "%s",
                options.bus_info.c_str());
  cap->version = 0x00060100;
  cap->device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
  cap->capabilities = cap->device_caps | V4L2_CAP_DEVICE_CAPS;
  umockdev_ioctl_data_unref(d);
  return complete_ioctl(client, 0, 0);
}

gboolean answer_enum_fmt(const CameraEmulation& cam, UMockdevIoctlClient* client,
                         UMockdevIoctlData* arg) {
  const auto& options = cam.camera->options();
  UMockdevIoctlData* d = resolve_arg(arg, sizeof(v4l2_fmtdesc));
  auto* f = view<v4l2_fmtdesc>(d);
  const std::uint32_t i = f->index;
  const bool ok = f->type == V4L2_BUF_TYPE_VIDEO_CAPTURE && i < options.formats.size();
  if (ok) {
    f->pixelformat = to_fourcc(options.formats[i]);
    f->flags = options.formats[i] == SimPixelFormat::Mjpeg ? V4L2_FMT_FLAG_COMPRESSED : 0;
    std::snprintf(reinterpret_cast<char*>(f->description), sizeof f->description, "%s",
                  options.formats[i] == SimPixelFormat::Mjpeg  ? "Motion-JPEG"
                  : options.formats[i] == SimPixelFormat::Yuyv ? "YUYV 4:2:2"
                                                               : "24-bit RGB 8-8-8");
  }
  umockdev_ioctl_data_unref(d);
  return complete_ioctl(client, ok ? 0 : -1, ok ? 0 : EINVAL);
}

// G_FMT reports the current format; S_FMT and TRY_FMT negotiate one, which only S_FMT keeps.
gboolean answer_fmt(CameraEmulation& cam, UMockdevIoctlClient* client, UMockdevIoctlData* arg,
                    unsigned long request) {
  const auto& options = cam.camera->options();
  UMockdevIoctlData* d = resolve_arg(arg, sizeof(v4l2_format));
  auto* f = view<v4l2_format>(d);
  if (f->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) {
    umockdev_ioctl_data_unref(d);
    return complete_ioctl(client, -1, EINVAL);
  }
  if (request != VIDIOC_G_FMT) {
    // Another process streaming from the camera (CameraFaults::busy), or this one already
    // streaming: uvcvideo refuses a format change with EBUSY.
    if (request == VIDIOC_S_FMT && (cam.streaming || options.faults.busy)) {
      umockdev_ioctl_data_unref(d);
      return complete_ioctl(client, -1, EBUSY);
    }
    // Like uvcvideo: an unknown format falls back to the first one, the size to the
    // sensor's (the simulated sensor has one mode).
    SimPixelFormat chosen = options.formats.front();
    for (auto candidate : options.formats)
      if (to_fourcc(candidate) == f->fmt.pix.pixelformat) chosen = candidate;
    if (request == VIDIOC_S_FMT) cam.format = chosen;
    CameraEmulation tmp_view;
    tmp_view.camera = cam.camera;
    tmp_view.format = chosen;
    fill_pix(tmp_view, f->fmt.pix);
  } else {
    fill_pix(cam, f->fmt.pix);
  }
  umockdev_ioctl_data_unref(d);
  return complete_ioctl(client, 0, 0);
}

// G_PARM and S_PARM alike: the simulated sensor runs at its own rate whatever is asked, as many
// webcams do.
gboolean answer_parm(const CameraEmulation& cam, UMockdevIoctlClient* client,
                     UMockdevIoctlData* arg) {
  const auto& options = cam.camera->options();
  UMockdevIoctlData* d = resolve_arg(arg, sizeof(v4l2_streamparm));
  auto* p = view<v4l2_streamparm>(d);
  p->parm.capture.capability = V4L2_CAP_TIMEPERFRAME;
  p->parm.capture.timeperframe.numerator = 1000;
  p->parm.capture.timeperframe.denominator =
      static_cast<std::uint32_t>(std::lround(options.fps * 1000));
  umockdev_ioctl_data_unref(d);
  return complete_ioctl(client, 0, 0);
}

gboolean answer_ctrl(CameraEmulation& cam, UMockdevIoctlClient* client, UMockdevIoctlData* arg,
                     unsigned long request) {
  UMockdevIoctlData* d = resolve_arg(arg, sizeof(v4l2_control));
  auto* c = view<v4l2_control>(d);
  const bool known = c->id == V4L2_CID_EXPOSURE_AUTO || c->id == V4L2_CID_EXPOSURE_ABSOLUTE ||
                     c->id == V4L2_CID_GAIN || c->id == V4L2_CID_BRIGHTNESS;
  if (known) {
    if (request == VIDIOC_S_CTRL)
      cam.controls[c->id] = c->value;
    else
      c->value = cam.controls[c->id];
  }
  umockdev_ioctl_data_unref(d);
  return complete_ioctl(client, known ? 0 : -1, known ? 0 : EINVAL);
}

gboolean answer_reqbufs(CameraEmulation& cam, UMockdevIoctlClient* client, UMockdevIoctlData* arg) {
  UMockdevIoctlData* d = resolve_arg(arg, sizeof(v4l2_requestbuffers));
  auto* r = view<v4l2_requestbuffers>(d);
  if (r->memory != V4L2_MEMORY_MMAP && r->memory != V4L2_MEMORY_USERPTR) {
    umockdev_ioctl_data_unref(d);
    return complete_ioctl(client, -1, EINVAL);
  }
  cam.memory = r->memory;
  r->count = std::min<std::uint32_t>(r->count, 32);
  cam.slots.assign(r->count, {});
  cam.queue.clear();
  r->capabilities = V4L2_BUF_CAP_SUPPORTS_MMAP | V4L2_BUF_CAP_SUPPORTS_USERPTR;
  umockdev_ioctl_data_unref(d);
  return complete_ioctl(client, 0, 0);
}

gboolean answer_querybuf(const CameraEmulation& cam, UMockdevIoctlClient* client,
                         UMockdevIoctlData* arg) {
  UMockdevIoctlData* d = resolve_arg(arg, sizeof(v4l2_buffer));
  auto* b = view<v4l2_buffer>(d);
  if (b->index >= cam.slots.size()) {
    umockdev_ioctl_data_unref(d);
    return complete_ioctl(client, -1, EINVAL);
  }
  v4l2_pix_format pix{};
  fill_pix(cam, pix);
  b->length = pix.sizeimage;
  b->memory = cam.memory;
  if (cam.memory == V4L2_MEMORY_MMAP) b->m.offset = b->index * ((pix.sizeimage + 4095) & ~4095u);
  umockdev_ioctl_data_unref(d);
  return complete_ioctl(client, 0, 0);
}

gboolean answer_qbuf(CameraEmulation& cam, UMockdevIoctlClient* client, UMockdevIoctlData* arg) {
  UMockdevIoctlData* d = resolve_arg(arg, sizeof(v4l2_buffer));
  auto* b = view<v4l2_buffer>(d);
  if (b->index >= cam.slots.size() || b->memory != cam.memory || cam.slots[b->index].queued) {
    umockdev_ioctl_data_unref(d);
    return complete_ioctl(client, -1, EINVAL);
  }
  auto& slot = cam.slots[b->index];
  if (cam.memory == V4L2_MEMORY_USERPTR) {
    v4l2_pix_format pix{};
    fill_pix(cam, pix);
    if (b->m.userptr == 0 || b->length < pix.sizeimage) {
      umockdev_ioctl_data_unref(d);
      return complete_ioctl(client, -1, EINVAL);
    }
    slot.userptr = b->m.userptr;
    slot.length = b->length;
  }
  slot.queued = true;
  cam.queue.push_back(b->index);
  umockdev_ioctl_data_unref(d);
  return complete_ioctl(client, 0, 0);
}

// Captures a frame into the oldest queued USERPTR buffer, written through to the client's memory.
gboolean answer_dqbuf(CameraEmulation& cam, UMockdevIoctlClient* client, UMockdevIoctlData* arg) {
  if (!cam.streaming) return complete_ioctl(client, -1, EINVAL);
  if (cam.queue.empty()) return complete_ioctl(client, -1, EAGAIN);
  if (cam.memory != V4L2_MEMORY_USERPTR)
    return complete_ioctl(client, -1, EAGAIN);  // see file comment
  const SimCamera::Capture c = cam.camera->capture(cam.format);
  if (c.status == SimCamera::Capture::Status::NotReady) return complete_ioctl(client, -1, EAGAIN);
  if (c.status == SimCamera::Capture::Status::Unplugged) return complete_ioctl(client, -1, ENODEV);
  if (c.status == SimCamera::Capture::Status::Eio) return complete_ioctl(client, -1, EIO);
  const unsigned index = cam.queue.front();
  cam.queue.pop_front();
  auto& slot = cam.slots[index];
  slot.queued = false;
  UMockdevIoctlData* d = resolve_arg(arg, sizeof(v4l2_buffer));
  auto* b = view<v4l2_buffer>(d);
  b->index = index;
  b->memory = V4L2_MEMORY_USERPTR;
  b->m.userptr = slot.userptr;
  b->length = slot.length;
  const std::size_t n = std::min<std::size_t>(c.bytes.size(), slot.length);
  UMockdevIoctlData* payload =
      umockdev_ioctl_data_resolve(d, offsetof(v4l2_buffer, m.userptr), slot.length, nullptr);
  std::memcpy(payload->data, c.bytes.data(), n);
  b = view<v4l2_buffer>(d);
  b->bytesused = static_cast<std::uint32_t>(n);
  b->sequence = c.sequence;
  b->flags = V4L2_BUF_FLAG_DONE | V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
  b->field = V4L2_FIELD_NONE;
  b->timestamp.tv_sec = static_cast<long>(c.timestamp_s);
  b->timestamp.tv_usec = static_cast<long>((c.timestamp_s - std::floor(c.timestamp_s)) * 1e6);
  umockdev_ioctl_data_unref(payload);
  umockdev_ioctl_data_unref(d);
  return complete_ioctl(client, 0, 0);
}

gboolean answer_streamon(CameraEmulation& cam, UMockdevIoctlClient* client) {
  if (cam.slots.empty()) return complete_ioctl(client, -1, EINVAL);
  cam.streaming = true;
  cam.camera->start_streaming();
  return complete_ioctl(client, 0, 0);
}

gboolean answer_streamoff(CameraEmulation& cam, UMockdevIoctlClient* client) {
  cam.streaming = false;
  cam.queue.clear();
  for (auto& s : cam.slots) s.queued = false;
  return complete_ioctl(client, 0, 0);
}

// umockdev's handle-ioctl signal for the video node, on umockdev's worker thread. FALSE (the
// default branch) tells umockdev the request was not handled here.
gboolean handle_v4l2_ioctl(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer user) {
  auto* cam = static_cast<CameraEmulation*>(user);
  std::lock_guard lock(cam->mutex);
  const unsigned long request = umockdev_ioctl_client_get_request(client);
  UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(client);
  if (cam->camera->unplugged()) return complete_ioctl(client, -1, ENODEV);

  switch (request) {
    case VIDIOC_QUERYCAP:
      return answer_querycap(*cam, client, arg);
    case VIDIOC_ENUM_FMT:
      return answer_enum_fmt(*cam, client, arg);
    case VIDIOC_G_FMT:
    case VIDIOC_S_FMT:
    case VIDIOC_TRY_FMT:
      return answer_fmt(*cam, client, arg, request);
    case VIDIOC_G_PARM:
    case VIDIOC_S_PARM:
      return answer_parm(*cam, client, arg);
    case VIDIOC_S_CTRL:
    case VIDIOC_G_CTRL:
      return answer_ctrl(*cam, client, arg, request);
    case VIDIOC_REQBUFS:
      return answer_reqbufs(*cam, client, arg);
    case VIDIOC_QUERYBUF:
      return answer_querybuf(*cam, client, arg);
    case VIDIOC_QBUF:
      return answer_qbuf(*cam, client, arg);
    case VIDIOC_DQBUF:
      return answer_dqbuf(*cam, client, arg);
    case VIDIOC_STREAMON:
      return answer_streamon(*cam, client);
    case VIDIOC_STREAMOFF:
      return answer_streamoff(*cam, client);
    default:
      return FALSE;
  }
}

}  // namespace

std::optional<int> EmulatedDevices::camera_control(std::uint32_t id) const {
  if (impl_->cameras.empty()) return std::nullopt;
  CameraEmulation* cam = impl_->cameras.front();
  std::lock_guard lock(cam->mutex);
  const auto it = cam->controls.find(id);
  if (it == cam->controls.end()) return std::nullopt;
  return it->second;
}

std::string EmulatedDevices::add_camera(std::shared_ptr<SimCamera> camera, int index) {
  auto* cam = new CameraEmulation();
  cam->camera = std::move(camera);
  cam->format = cam->camera->options().formats.front();
  impl_->cameras.push_back(cam);
  cam->handler = umockdev_ioctl_base_new();
  g_signal_connect(cam->handler, "handle-ioctl", G_CALLBACK(handle_v4l2_ioctl), cam);
  const std::string name = "video" + std::to_string(index);
  const std::string node = "/dev/" + name;
  GError* error = nullptr;
  if (!umockdev_testbed_attach_ioctl(impl_->testbed, node.c_str(), cam->handler, &error)) {
    const std::string msg = error ? error->message : "unknown";
    if (error) g_error_free(error);
    throw std::runtime_error("umockdev_testbed_attach_ioctl: " + msg);
  }
  const std::string description =
      "P: /devices/pci0000:00/usb1/1-3/1-3:1.0/video4linux/" + name + "\nN: " + name +
      "\nE: SUBSYSTEM=video4linux\nE: DEVNAME=" + node +
      "\nA: name=" + cam->camera->options().card + "\\n\nA: index=0\\n\n";
  if (!umockdev_testbed_add_from_string(impl_->testbed, description.c_str(), &error)) {
    const std::string msg = error ? error->message : "unknown";
    if (error) g_error_free(error);
    throw std::runtime_error("umockdev_testbed_add_from_string: " + msg);
  }
  return node;
}

}  // namespace scanmesh::sim
