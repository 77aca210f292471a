#include "scanmesh/drivers/usb_transport.h"

#include <libusb.h>

#include <algorithm>
#include <cstdio>
#include <cstring>

#include "scanmesh/core/errors.h"

namespace scanmesh::drivers {
namespace {

constexpr std::uint8_t kClassCdcComm = 0x02;
constexpr std::uint8_t kClassCdcData = 0x0a;
constexpr std::uint8_t kClassVendor = 0xff;
// USB CDC PSTN subclass 1.2, table 13 / §6.3.10-12.
constexpr std::uint8_t kSetLineCoding = 0x20;
constexpr std::uint8_t kSetControlLineState = 0x22;
// bmRequestType: host-to-device, class request, interface recipient.
constexpr std::uint8_t kClassInterfaceOut = 0x21;

std::string hex4(unsigned v) {
  char b[8];
  std::snprintf(b, sizeof b, "%04x", v & 0xffffu);
  return b;
}

std::string usb_name(int bus, int address, std::uint16_t vid, std::uint16_t pid) {
  char b[64];
  std::snprintf(b, sizeof b, "usb %03d:%03d (%04x:%04x)", bus, address, vid, pid);
  return b;
}

std::string problem_text(int code) {
  switch (code) {
    case LIBUSB_ERROR_NO_DEVICE:
      return "unplugged (LIBUSB_ERROR_NO_DEVICE)";
    case LIBUSB_ERROR_ACCESS:
      return "access denied (install configs/udev/60-scanmesh.rules, see docs/hardware.md)";
    case LIBUSB_ERROR_BUSY:
      return "busy: another program or driver claimed the interface";
    case LIBUSB_ERROR_PIPE:
      return "endpoint stalled (LIBUSB_ERROR_PIPE)";
    case LIBUSB_ERROR_TIMEOUT:
      return "transfer timed out";
    default:
      return std::string("libusb: ") + libusb_error_name(code);
  }
}

struct Endpoints {
  int comm_interface = -1;  //!< CDC communication interface (class requests), if any
  int data_interface = -1;
  unsigned char in = 0, out = 0;
  int in_packet = 64;
};

Endpoints find_endpoints(const libusb_config_descriptor& config) {
  Endpoints e;
  for (int i = 0; i < config.bNumInterfaces; ++i) {
    const libusb_interface& itf = config.interface[i];
    if (itf.num_altsetting < 1) continue;
    const libusb_interface_descriptor& alt = itf.altsetting[0];
    if (alt.bInterfaceClass == kClassCdcComm && e.comm_interface < 0)
      e.comm_interface = alt.bInterfaceNumber;
    if (alt.bInterfaceClass != kClassCdcData && alt.bInterfaceClass != kClassVendor) continue;
    unsigned char in = 0, out = 0;
    int in_packet = 64;
    for (int k = 0; k < alt.bNumEndpoints; ++k) {
      const libusb_endpoint_descriptor& ep = alt.endpoint[k];
      if ((ep.bmAttributes & LIBUSB_TRANSFER_TYPE_MASK) != LIBUSB_TRANSFER_TYPE_BULK) continue;
      if (ep.bEndpointAddress & LIBUSB_ENDPOINT_IN) {
        in = ep.bEndpointAddress;
        in_packet = std::max<int>(ep.wMaxPacketSize, 8);
      } else {
        out = ep.bEndpointAddress;
      }
    }
    if (in && out && e.data_interface < 0) {
      e.data_interface = alt.bInterfaceNumber;
      e.in = in;
      e.out = out;
      e.in_packet = in_packet;
    }
  }
  return e;
}

bool has_cdc_comm(libusb_device* dev) {
  libusb_config_descriptor* config = nullptr;
  if (libusb_get_active_config_descriptor(dev, &config) != 0 &&
      libusb_get_config_descriptor(dev, 0, &config) != 0)
    return false;
  const bool cdc = find_endpoints(*config).comm_interface >= 0;
  libusb_free_config_descriptor(config);
  return cdc;
}

class UsbTransport final : public Transport {
 public:
  UsbTransport(libusb_context* ctx, libusb_device_handle* handle, std::string name, Endpoints ep)
      : ctx_(ctx), handle_(handle), name_(std::move(name)), ep_(ep) {}
  ~UsbTransport() override { close(); }

  void claim(int baud) {
    for (int itf : {ep_.comm_interface, ep_.data_interface}) {
      if (itf < 0) continue;
      const int active = libusb_kernel_driver_active(handle_, itf);
      if (active == 1) {
        const int r = libusb_detach_kernel_driver(handle_, itf);
        if (r != 0)
          throw DeviceError(name_, "cannot detach the kernel driver from interface " +
                                       std::to_string(itf) + ": " + problem_text(r));
        detached_.push_back(itf);
      } else if (active == LIBUSB_ERROR_NO_DEVICE) {
        throw DeviceError(name_, problem_text(active));
      }
      const int r = libusb_claim_interface(handle_, itf);
      if (r != 0)
        throw DeviceError(name_,
                          "cannot claim interface " + std::to_string(itf) + ": " + problem_text(r));
      claimed_.push_back(itf);
    }
    if (ep_.comm_interface >= 0) {
      // 8N1 at `baud`: dwDTERate (LE), bCharFormat 0 (1 stop bit), bParityType 0, bDataBits 8.
      unsigned char coding[7] = {static_cast<unsigned char>(baud & 0xff),
                                 static_cast<unsigned char>((baud >> 8) & 0xff),
                                 static_cast<unsigned char>((baud >> 16) & 0xff),
                                 static_cast<unsigned char>((baud >> 24) & 0xff),
                                 0,
                                 0,
                                 8};
      const auto index = static_cast<std::uint16_t>(ep_.comm_interface);
      int r = libusb_control_transfer(handle_, kClassInterfaceOut, kSetLineCoding, 0, index, coding,
                                      sizeof coding, 1000);
      if (r != static_cast<int>(sizeof coding))
        throw DeviceError(name_, "SET_LINE_CODING failed: " + problem_text(r < 0 ? r : -99));
      // DTR | RTS: an Arduino's CDC firmware only transmits once DTR is raised.
      r = libusb_control_transfer(handle_, kClassInterfaceOut, kSetControlLineState, 0x0003, index,
                                  nullptr, 0, 1000);
      if (r != 0) throw DeviceError(name_, "SET_CONTROL_LINE_STATE failed: " + problem_text(r));
    }
  }

  void write(std::string_view bytes) override {
    check_open();
    std::string copy(bytes);
    std::size_t done = 0;
    bool cleared = false;
    while (done < copy.size()) {
      int transferred = 0;
      const int r = libusb_bulk_transfer(handle_, ep_.out,
                                         reinterpret_cast<unsigned char*>(copy.data() + done),
                                         static_cast<int>(copy.size() - done), &transferred, 1000);
      done += static_cast<std::size_t>(std::max(transferred, 0));
      if (r == 0) continue;
      if (r == LIBUSB_ERROR_PIPE && !cleared) {
        cleared = true;
        libusb_clear_halt(handle_, ep_.out);
        continue;
      }
      if (r == LIBUSB_ERROR_TIMEOUT) throw DeviceError(name_, "write stalled for 1000 ms");
      throw DeviceError(name_, "write: " + problem_text(r));
    }
  }

  std::optional<std::string> read_line(std::chrono::milliseconds timeout) override {
    check_open();
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    std::vector<unsigned char> buffer(static_cast<std::size_t>(ep_.in_packet) * 4);
    bool cleared = false;
    for (;;) {
      if (auto line = lines_.pop_line()) return line;
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) return std::nullopt;
      int transferred = 0;
      const int r = libusb_bulk_transfer(
          handle_, ep_.in, buffer.data(), static_cast<int>(buffer.size()), &transferred,
          static_cast<unsigned>(std::max<long long>(left.count(), 1)));
      if (transferred > 0)
        lines_.append(std::string_view(reinterpret_cast<const char*>(buffer.data()),
                                       static_cast<std::size_t>(transferred)));
      if (r == 0 || r == LIBUSB_ERROR_OVERFLOW) continue;
      if (r == LIBUSB_ERROR_TIMEOUT) {
        if (auto line = lines_.pop_line()) return line;
        return std::nullopt;
      }
      if (r == LIBUSB_ERROR_PIPE && !cleared) {
        cleared = true;
        libusb_clear_halt(handle_, ep_.in);
        continue;
      }
      throw DeviceError(name_, "read: " + problem_text(r));
    }
  }

  void discard_input() override { lines_.clear(); }

  void close() override {
    if (!handle_) return;
    for (int itf : claimed_) libusb_release_interface(handle_, itf);
    for (int itf : detached_) libusb_attach_kernel_driver(handle_, itf);
    libusb_close(handle_);
    handle_ = nullptr;
    libusb_exit(ctx_);
    ctx_ = nullptr;
  }

  std::string name() const override { return name_; }

 private:
  void check_open() const {
    if (!handle_) throw DeviceError(name_, "transport is closed");
  }

  libusb_context* ctx_;
  libusb_device_handle* handle_;
  std::string name_;
  Endpoints ep_;
  std::vector<int> claimed_, detached_;
  LineBuffer lines_;
};

bool matches(const UsbSerialOptions& o, libusb_device* dev, const libusb_device_descriptor& d) {
  if (o.bus >= 0 && libusb_get_bus_number(dev) != o.bus) return false;
  if (o.address >= 0 && libusb_get_device_address(dev) != o.address) return false;
  if (o.vendor_id != 0 && d.idVendor != o.vendor_id) return false;
  if (o.product_id != 0 && d.idProduct != o.product_id) return false;
  if (o.vendor_id == 0 && o.bus < 0)
    return known_board_kind(d.idVendor, d.idProduct, d.bDeviceClass, has_cdc_comm(dev)).has_value();
  return true;
}

}  // namespace

std::optional<std::string> known_board_kind(std::uint16_t vid, std::uint16_t pid,
                                            std::uint8_t device_class, bool has_cdc_interface) {
  if (vid == 0x1a86 && pid == 0x7523) return "CH340";
  if (vid == 0x0403 && pid == 0x6001) return "FTDI";
  if (vid == 0x2341 || vid == 0x2a03) return "Arduino";
  if (device_class == kClassCdcComm || has_cdc_interface) return "CDC-ACM";
  return std::nullopt;
}

std::vector<UsbBoardInfo> list_usb_boards() {
  std::vector<UsbBoardInfo> boards;
  libusb_context* ctx = nullptr;
  if (libusb_init(&ctx) != 0) return boards;
  libusb_device** list = nullptr;
  const ssize_t n = libusb_get_device_list(ctx, &list);
  for (ssize_t i = 0; i < n; ++i) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(list[i], &d) != 0) continue;
    const auto kind =
        known_board_kind(d.idVendor, d.idProduct, d.bDeviceClass, has_cdc_comm(list[i]));
    if (!kind) continue;
    boards.push_back({libusb_get_bus_number(list[i]), libusb_get_device_address(list[i]),
                      d.idVendor, d.idProduct, *kind});
  }
  if (n >= 0) libusb_free_device_list(list, 1);
  libusb_exit(ctx);
  return boards;
}

UsbSerialOptions parse_usb_board_spec(const std::string& spec) {
  UsbSerialOptions o;
  unsigned a = 0, b = 0;
  char tail = 0;
  if (std::sscanf(spec.c_str(), "usb:%u:%u%c", &a, &b, &tail) == 2 && a < 256 && b < 256) {
    o.bus = static_cast<int>(a);
    o.address = static_cast<int>(b);
    return o;
  }
  if (spec.size() == 9 && spec[4] == ':' &&
      std::sscanf(spec.c_str(), "%4x:%4x%c", &a, &b, &tail) == 2) {
    o.vendor_id = static_cast<std::uint16_t>(a);
    o.product_id = static_cast<std::uint16_t>(b);
    return o;
  }
  throw InvalidInputError("board '" + spec +
                          "' is neither a tty path, VID:PID (1a86:7523) nor usb:BUS:ADDR");
}

std::unique_ptr<Transport> open_usb_transport(const UsbSerialOptions& options) {
  libusb_context* ctx = nullptr;
  if (const int r = libusb_init(&ctx); r != 0)
    throw DeviceError("usb", "libusb_init failed: " + problem_text(r));
  libusb_device** list = nullptr;
  const ssize_t n = libusb_get_device_list(ctx, &list);
  libusb_device* found = nullptr;
  libusb_device_descriptor desc{};
  for (ssize_t i = 0; i < n && !found; ++i) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(list[i], &d) != 0) continue;
    if (matches(options, list[i], d)) {
      found = libusb_ref_device(list[i]);
      desc = d;
    }
  }
  if (n >= 0) libusb_free_device_list(list, 1);
  const std::string wanted =
      options.vendor_id ? hex4(options.vendor_id) + ":" + hex4(options.product_id)
      : options.bus >= 0
          ? "usb:" + std::to_string(options.bus) + ":" + std::to_string(options.address)
          : std::string("usb board");
  if (!found) {
    libusb_exit(ctx);
    throw DeviceError(wanted, "no such USB device (see `scanmesh devices`)");
  }
  const std::string name = usb_name(libusb_get_bus_number(found), libusb_get_device_address(found),
                                    desc.idVendor, desc.idProduct);
  libusb_config_descriptor* config = nullptr;
  int r = libusb_get_active_config_descriptor(found, &config);
  if (r != 0) r = libusb_get_config_descriptor(found, 0, &config);
  if (r != 0) {
    libusb_unref_device(found);
    libusb_exit(ctx);
    throw DeviceError(name, "cannot read the configuration descriptor: " + problem_text(r));
  }
  const Endpoints ep = find_endpoints(*config);
  libusb_free_config_descriptor(config);
  if (ep.data_interface < 0) {
    libusb_unref_device(found);
    libusb_exit(ctx);
    throw DeviceError(name, "no interface with a bulk IN and a bulk OUT endpoint");
  }
  libusb_device_handle* handle = nullptr;
  r = libusb_open(found, &handle);
  libusb_unref_device(found);
  if (r != 0) {
    libusb_exit(ctx);
    throw DeviceError(name, "cannot open: " + problem_text(r));
  }
  auto transport = std::make_unique<UsbTransport>(ctx, handle, name, ep);
  transport->claim(options.baud);
  return transport;
}

}  // namespace scanmesh::drivers
