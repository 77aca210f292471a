#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>

#include "scanmesh/core/errors.h"
#include "scanmesh/drivers/camera.h"

namespace scanmesh::drivers {
namespace {

int xioctl(int fd, unsigned long request, void* arg) {
  int r;
  do r = ::ioctl(fd, request, arg);
  while (r == -1 && errno == EINTR);
  return r;
}

std::uint32_t fourcc(PixelFormat f) {
  switch (f) {
    case PixelFormat::Yuyv:
      return V4L2_PIX_FMT_YUYV;
    case PixelFormat::Mjpeg:
      return V4L2_PIX_FMT_MJPEG;
    case PixelFormat::Rgb24:
      return V4L2_PIX_FMT_RGB24;
  }
  return 0;
}

std::optional<PixelFormat> from_fourcc(std::uint32_t f) {
  if (f == V4L2_PIX_FMT_YUYV) return PixelFormat::Yuyv;
  if (f == V4L2_PIX_FMT_MJPEG || f == V4L2_PIX_FMT_JPEG) return PixelFormat::Mjpeg;
  if (f == V4L2_PIX_FMT_RGB24) return PixelFormat::Rgb24;
  return std::nullopt;
}

std::string fourcc_text(std::uint32_t f) {
  std::string s(4, ' ');
  for (int i = 0; i < 4; ++i) s[i] = static_cast<char>((f >> (8 * i)) & 0xff);
  return s;
}

std::string c_string(const __u8* p, std::size_t n) {
  const auto* c = reinterpret_cast<const char*>(p);
  return std::string(c, strnlen(c, n));
}

std::string open_problem(int e) {
  switch (e) {
    case ENOENT:
      return "no such device node";
    case EACCES:
      return "permission denied (add the user to group 'video' or install "
             "configs/udev/60-scanmesh.rules, see docs/hardware.md)";
    case EBUSY:
      return "busy: another program is using the camera (EBUSY)";
    case ENODEV:
    case ENXIO:
      return "unplugged (ENODEV)";
    default:
      return std::strerror(e);
  }
}

// Opens `path` and reads its capabilities and formats; returns the fd (caller closes).
int open_and_query(const std::string& path, CameraInfo& info) {
  const int fd = ::open(path.c_str(),
                        O_RDWR | O_NONBLOCK | O_CLOEXEC);  // non-atomic: a device node, not a file
  if (fd < 0) throw DeviceError(path, "cannot open: " + open_problem(errno));
  v4l2_capability cap{};
  if (xioctl(fd, VIDIOC_QUERYCAP, &cap) != 0) {
    const int e = errno;
    ::close(fd);
    throw DeviceError(path,
                      std::string("not a V4L2 device (VIDIOC_QUERYCAP: ") + std::strerror(e) + ")");
  }
  const std::uint32_t caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
  info.path = path;
  info.card = c_string(cap.card, sizeof cap.card);
  info.driver = c_string(cap.driver, sizeof cap.driver);
  info.bus_info = c_string(cap.bus_info, sizeof cap.bus_info);
  if (!(caps & V4L2_CAP_VIDEO_CAPTURE)) {
    ::close(fd);
    throw DeviceError(path, "'" + info.card + "' is not a video capture device");
  }
  for (std::uint32_t i = 0; i < 64; ++i) {
    v4l2_fmtdesc d{};
    d.index = i;
    d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(fd, VIDIOC_ENUM_FMT, &d) != 0) break;
    info.all_formats.push_back(fourcc_text(d.pixelformat));
    if (const auto f = from_fourcc(d.pixelformat)) info.formats.push_back(*f);
  }
  if (!(caps & V4L2_CAP_STREAMING)) {
    ::close(fd);
    throw DeviceError(path, "'" + info.card + "' does not support streaming I/O");
  }
  return fd;
}

}  // namespace

std::vector<CameraInfo> list_cameras() {
  std::vector<CameraInfo> cameras;
  std::error_code ec;
  std::vector<std::string> nodes;
  // sysfs names the V4L2 nodes (udev does the same); umockdev redirects /sys, so emulated
  // cameras are found the same way.
  for (const auto& entry : std::filesystem::directory_iterator("/sys/class/video4linux", ec)) {
    const std::string name = entry.path().filename().string();
    if (name.starts_with("video")) nodes.push_back("/dev/" + name);
  }
  std::sort(nodes.begin(), nodes.end());
  for (const auto& node : nodes) {
    try {
      CameraInfo info;
      ::close(open_and_query(node, info));
      cameras.push_back(std::move(info));
    } catch (const DeviceError&) {
      // metadata nodes of UVC cameras, nodes we may not open: not cameras for us
    }
  }
  return cameras;
}

V4l2Camera::V4l2Camera(const std::string& device, const CameraSettings& settings) {
  path_ = device;
  if (!device.starts_with("/")) {
    for (const auto& c : list_cameras())
      if (c.card == device || c.bus_info == device) {
        path_ = c.path;
        break;
      }
    if (path_ == device)
      throw DeviceError(device, "no camera with this card name or bus (see `scanmesh devices`)");
  }
  fd_ = open_and_query(path_, info_);
  try {
    configure(settings);
  } catch (...) {
    stop();
    ::close(fd_);
    fd_ = -1;
    throw;
  }
}

V4l2Camera::~V4l2Camera() {
  stop();
  if (fd_ >= 0) ::close(fd_);
}

void V4l2Camera::fail(const std::string& what, int err) const {
  if (err == ENODEV || err == ENXIO) throw DeviceError(path_, "unplugged during " + what);
  if (err == EBUSY) throw DeviceError(path_, what + ": busy (another program streams from it)");
  if (err == EIO) throw DeviceError(path_, what + ": I/O error (EIO)");
  throw DeviceError(path_, what + ": " + std::strerror(err));
}

void V4l2Camera::set_exposure(int exposure_100us) {
  set_control(V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL, "auto exposure off");
  set_control(V4L2_CID_EXPOSURE_ABSOLUTE, exposure_100us, "exposure");
}

void V4l2Camera::set_control(std::uint32_t id, std::int32_t value, const char* what) {
  v4l2_control c{};
  c.id = id;
  c.value = value;
  if (xioctl(fd_, VIDIOC_S_CTRL, &c) != 0) {
    if (errno == EINVAL || errno == ENOTTY)
      throw DeviceError(path_, std::string("control '") + what + "' is not supported");
    fail(std::string("setting ") + what, errno);
  }
}

void V4l2Camera::configure(const CameraSettings& s) {
  settings_ = s;
  if (s.buffer_count < 2 || s.buffer_count > 32)
    throw InvalidInputError("camera buffer count must be 2..32");
  if (std::find(info_.formats.begin(), info_.formats.end(), s.format) == info_.formats.end()) {
    std::string offered;
    for (const auto& f : info_.all_formats) offered += (offered.empty() ? "" : ", ") + f;
    throw DeviceError(path_, "unsupported format " + to_string(s.format) + " (the camera offers " +
                                 (offered.empty() ? std::string("none") : offered) + ")");
  }
  v4l2_format fmt{};
  fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  fmt.fmt.pix.width = static_cast<std::uint32_t>(s.width);
  fmt.fmt.pix.height = static_cast<std::uint32_t>(s.height);
  fmt.fmt.pix.pixelformat = fourcc(s.format);
  fmt.fmt.pix.field = V4L2_FIELD_NONE;
  if (xioctl(fd_, VIDIOC_S_FMT, &fmt) != 0) fail("VIDIOC_S_FMT", errno);
  if (fmt.fmt.pix.pixelformat != fourcc(s.format))
    throw DeviceError(path_, "unsupported format " + to_string(s.format) + " (the driver chose " +
                                 fourcc_text(fmt.fmt.pix.pixelformat) + ")");
  descriptor_.path = path_;
  descriptor_.card = info_.card;
  descriptor_.driver = info_.driver;
  descriptor_.bus_info = info_.bus_info;
  descriptor_.width = static_cast<int>(fmt.fmt.pix.width);
  descriptor_.height = static_cast<int>(fmt.fmt.pix.height);
  descriptor_.format = s.format;
  bytes_per_line_ = fmt.fmt.pix.bytesperline;
  size_image_ = fmt.fmt.pix.sizeimage;
  if (size_image_ == 0)
    size_image_ = static_cast<std::uint32_t>(descriptor_.width * descriptor_.height * 3);

  v4l2_streamparm parm{};
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  parm.parm.capture.timeperframe.numerator = 1000;
  parm.parm.capture.timeperframe.denominator =
      static_cast<std::uint32_t>(std::lround(s.fps * 1000.0));
  descriptor_.fps = s.fps;
  if (xioctl(fd_, VIDIOC_S_PARM, &parm) == 0 && parm.parm.capture.timeperframe.numerator > 0)
    descriptor_.fps = static_cast<double>(parm.parm.capture.timeperframe.denominator) /
                      parm.parm.capture.timeperframe.numerator;

  // A laser scanner needs a fixed exposure: automatic exposure would dim the laser line.
  if (s.exposure) set_exposure(*s.exposure);
  if (s.gain) {
    v4l2_control c{V4L2_CID_AUTOGAIN, 0};
    xioctl(fd_, VIDIOC_S_CTRL, &c);  // many UVC cameras have no auto gain: not an error
    set_control(V4L2_CID_GAIN, *s.gain, "gain");
  }
  if (s.brightness) set_control(V4L2_CID_BRIGHTNESS, *s.brightness, "brightness");

  v4l2_requestbuffers req{};
  req.count = static_cast<std::uint32_t>(s.buffer_count);
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = s.io == IoMethod::Mmap ? V4L2_MEMORY_MMAP : V4L2_MEMORY_USERPTR;
  if (xioctl(fd_, VIDIOC_REQBUFS, &req) != 0) {
    if (errno == EINVAL)
      throw DeviceError(path_, std::string("does not support ") +
                                   (s.io == IoMethod::Mmap ? "MMAP" : "USERPTR") + " streaming");
    fail("VIDIOC_REQBUFS", errno);
  }
  if (req.count < 2)
    throw DeviceError(path_, "granted only " + std::to_string(req.count) + " buffer(s)");
  buffers_.resize(req.count);
  for (std::uint32_t i = 0; i < req.count; ++i) {
    Buffer& b = buffers_[i];
    if (s.io == IoMethod::Mmap) {
      v4l2_buffer buf{};
      buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      buf.memory = V4L2_MEMORY_MMAP;
      buf.index = i;
      if (xioctl(fd_, VIDIOC_QUERYBUF, &buf) != 0) fail("VIDIOC_QUERYBUF", errno);
      void* p = ::mmap(nullptr, buf.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, buf.m.offset);
      if (p == MAP_FAILED) {
        // mmap(2): ENODEV means this file cannot be mapped, not that the camera is gone.
        const int e = errno;
        if (e == ENODEV)
          throw DeviceError(path_, "mmap of buffer " + std::to_string(i) +
                                       ": the node does not support memory mapping (use USERPTR)");
        fail("mmap of buffer " + std::to_string(i), e);
      }
      b.start = p;
      b.length = buf.length;
    } else {
      b.owned.assign(size_image_, 0);
      b.start = b.owned.data();
      b.length = b.owned.size();
    }
  }
  for (std::uint32_t i = 0; i < req.count; ++i) queue(i);
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(fd_, VIDIOC_STREAMON, &type) != 0) fail("VIDIOC_STREAMON", errno);
  streaming_ = true;
}

void V4l2Camera::queue(unsigned index) {
  v4l2_buffer buf{};
  buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buf.index = index;
  if (settings_.io == IoMethod::Mmap) {
    buf.memory = V4L2_MEMORY_MMAP;
  } else {
    buf.memory = V4L2_MEMORY_USERPTR;
    buf.m.userptr = reinterpret_cast<unsigned long>(buffers_[index].start);
    buf.length = static_cast<std::uint32_t>(buffers_[index].length);
  }
  if (xioctl(fd_, VIDIOC_QBUF, &buf) != 0) fail("VIDIOC_QBUF", errno);
}

bool V4l2Camera::try_dequeue(Frame& frame) {
  v4l2_buffer buf{};
  buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buf.memory = settings_.io == IoMethod::Mmap ? V4L2_MEMORY_MMAP : V4L2_MEMORY_USERPTR;
  if (xioctl(fd_, VIDIOC_DQBUF, &buf) != 0) {
    if (errno == EAGAIN) return false;
    fail("VIDIOC_DQBUF", errno);
  }
  if (buf.index >= buffers_.size())
    throw DeviceError(path_, "driver returned buffer index " + std::to_string(buf.index));
  const Buffer& b = buffers_[buf.index];
  // Sequence gaps are frames the driver dropped (no free buffer, USB bandwidth).
  std::uint32_t gap = 0;
  if (last_sequence_ && buf.sequence > *last_sequence_ + 1)
    gap = buf.sequence - *last_sequence_ - 1;
  last_sequence_ = buf.sequence;
  dropped_ += gap;
  frame.dropped_before += gap;
  if (buf.flags & V4L2_BUF_FLAG_ERROR) {
    ++dropped_;
    ++frame.dropped_before;
    queue(buf.index);
    return false;
  }
  const std::size_t used = std::min<std::size_t>(buf.bytesused, b.length);
  const std::span<const std::uint8_t> bytes(static_cast<const std::uint8_t*>(b.start), used);
  frame.format = settings_.format;
  frame.sequence = buf.sequence;
  frame.timestamp_s = static_cast<double>(buf.timestamp.tv_sec) + buf.timestamp.tv_usec * 1e-6;
  const std::string source = path_ + " frame " + std::to_string(buf.sequence);
  try {
    frame.rgb = decode_frame(settings_.format, bytes, descriptor_.width, descriptor_.height,
                             settings_.format == PixelFormat::Mjpeg ? 0 : bytes_per_line_, source);
  } catch (const FileFormatError&) {
    queue(buf.index);
    throw;
  }
  if (settings_.format == PixelFormat::Mjpeg)
    frame.original.assign(bytes.begin(), bytes.end());
  else
    frame.original.clear();
  queue(buf.index);
  return true;
}

Frame V4l2Camera::grab() {
  if (fd_ < 0 || !streaming_) throw DeviceError(path_, "camera is not streaming");
  const auto deadline = std::chrono::steady_clock::now() + settings_.timeout;
  Frame frame;
  frame.dropped_before = flushed_dropped_;
  flushed_dropped_ = 0;
  int corrupt = 0;
  std::string last_corruption;
  for (;;) {
    try {
      if (try_dequeue(frame)) return frame;
    } catch (const FileFormatError& e) {
      // A corrupt frame (damaged MJPEG, short YUYV) is dropped like the camera had dropped it;
      // only a run of them is an error.
      ++dropped_;
      ++frame.dropped_before;
      last_corruption = e.what();
      if (++corrupt >= 3) throw DeviceError(path_, "3 corrupt frames in a row: " + last_corruption);
      continue;
    }
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0)
      throw DeviceError(path_,
                        "no frame within " + std::to_string(settings_.timeout.count()) + " ms");
    // poll() in slices of 1 ms followed by a non-blocking DQBUF: on a real node poll
    // wakes when a buffer is done; on an emulated node (a socket, docs/testing.md) it never
    // signals POLLIN and the slice bounds the latency.
    pollfd p{fd_, POLLIN | POLLPRI, 0};
    const int r = ::poll(&p, 1, static_cast<int>(std::min<long long>(left.count(), 1)));
    if (r < 0 && errno != EINTR) fail("poll", errno);
    if (r > 0 && (p.revents & (POLLERR | POLLHUP | POLLNVAL)) && !(p.revents & POLLIN))
      throw DeviceError(path_, "unplugged (poll reported a hang-up)");
  }
}

void V4l2Camera::flush() {
  // Stale frames are the ones already in the driver's buffers: at most one per buffer. Reading
  // on until none is ready made the count depend on the host's speed: a host slower than the
  // frame period always finds a new frame (up to 64 were read), so the frames a scan step used
  // up, and with them the step a camera fault hits, varied with the machine's load.
  for (std::size_t i = 0; i < buffers_.size(); ++i) {
    Frame f;
    bool got = false;
    try {
      got = try_dequeue(f);
    } catch (const FileFormatError&) {
      got = true;
      ++f.dropped_before;
    }
    // Frames lost before a flushed frame are still reported, with the next frame returned.
    flushed_dropped_ += f.dropped_before;
    if (!got) return;
  }
}

void V4l2Camera::stop() noexcept {
  if (fd_ >= 0 && streaming_) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    xioctl(fd_, VIDIOC_STREAMOFF, &type);
  }
  streaming_ = false;
  for (auto& b : buffers_)
    if (b.owned.empty() && b.start) ::munmap(b.start, b.length);
  if (fd_ >= 0 && !buffers_.empty()) {
    v4l2_requestbuffers req{};
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = settings_.io == IoMethod::Mmap ? V4L2_MEMORY_MMAP : V4L2_MEMORY_USERPTR;
    xioctl(fd_, VIDIOC_REQBUFS, &req);
  }
  buffers_.clear();
}

}  // namespace scanmesh::drivers
