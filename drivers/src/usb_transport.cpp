#include "scanmesh/drivers/usb_transport.h"

#include <libusb.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
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

// Vendor requests of the USB-serial bridges (bmRequestType: vendor, device recipient).
constexpr std::uint8_t kVendorOut = 0x40, kVendorIn = 0xc0;
// WCH CH340/CH341: registers written in pairs with WRITE_REG (wValue = reg2 << 8 | reg1,
// wIndex = val2 << 8 | val1); the baud rate is the prescaler (0x12) / divisor (0x13) pair, the
// line control the 0x18 / 0x25 pair; modem lines are set active low with MODEM_CTRL.
constexpr std::uint8_t kCh34xReadVersion = 0x5f, kCh34xSerialInit = 0xa1, kCh34xWriteReg = 0x9a,
                       kCh34xModemCtrl = 0xa4;
constexpr std::uint16_t kCh34xRegBaud = 0x1312, kCh34xRegLcr = 0x2518;
constexpr std::uint8_t kCh34xLcrEnableRxTx8 = 0xc3;  // RX on, TX on, 8 data bits
constexpr std::uint8_t kCh34xDtr = 0x20, kCh34xRts = 0x40;
// FTDI FT232 (BM/R/X/H single port): SIO requests on interface A.
constexpr std::uint8_t kFtdiReset = 0x00, kFtdiModemCtrl = 0x01, kFtdiSetBaud = 0x03,
                       kFtdiSetData = 0x04;
constexpr std::uint16_t kFtdiDtrRtsOn = 0x0303;  // both lines high, both masks set
constexpr int kFtdiStatusBytes = 2;  // every bulk IN packet starts with modem + line status

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
  UsbTransport(libusb_context* ctx, libusb_device_handle* handle, std::string name, Endpoints ep,
               UsbBridge bridge)
      : ctx_(ctx), handle_(handle), name_(std::move(name)), ep_(ep), bridge_(bridge) {}
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
    if (bridge_ == UsbBridge::Ch34x) return setup_ch34x(baud);
    if (bridge_ == UsbBridge::Ftdi) return setup_ftdi(baud);
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

  // One vendor control request; throws naming the request on any failure.
  void vendor_out(std::uint8_t request, std::uint16_t value, std::uint16_t index,
                  const char* what) {
    const int r =
        libusb_control_transfer(handle_, kVendorOut, request, value, index, nullptr, 0, 1000);
    if (r != 0) throw DeviceError(name_, std::string(what) + " failed: " + problem_text(r));
  }

  void setup_ch34x(int baud) {
    unsigned char version[2] = {0, 0};
    const int r = libusb_control_transfer(handle_, kVendorIn, kCh34xReadVersion, 0, 0, version,
                                          sizeof version, 1000);
    if (r != static_cast<int>(sizeof version))
      throw DeviceError(name_, "CH34x READ_VERSION failed: " + problem_text(r < 0 ? r : -99));
    vendor_out(kCh34xSerialInit, 0, 0, "CH34x SERIAL_INIT");
    // Bit 7 of the prescaler byte: send what arrived at once instead of waiting for a full
    // 32-byte packet (chips newer than version 0x27).
    std::uint16_t reg = ch34x_baud_register(baud);
    if (version[0] > 0x27) reg |= 0x80;
    vendor_out(kCh34xWriteReg, kCh34xRegBaud, reg, "CH34x baud rate");
    vendor_out(kCh34xWriteReg, kCh34xRegLcr, kCh34xLcrEnableRxTx8, "CH34x line control");
    // Active low: the bits of the lines to raise are cleared.
    vendor_out(kCh34xModemCtrl, static_cast<std::uint16_t>(~(kCh34xDtr | kCh34xRts) & 0xff), 0,
               "CH34x MODEM_CTRL");
  }

  void setup_ftdi(int baud) {
    vendor_out(kFtdiReset, 0, 0, "FTDI RESET");
    const std::uint32_t divisor = ftdi_baud_divisor(baud);
    vendor_out(kFtdiSetBaud, static_cast<std::uint16_t>(divisor & 0xffff),
               static_cast<std::uint16_t>(divisor >> 16), "FTDI SET_BAUD_RATE");
    vendor_out(kFtdiSetData, 8, 0, "FTDI SET_DATA (8N1)");
    vendor_out(kFtdiModemCtrl, kFtdiDtrRtsOn, 0, "FTDI MODEM_CTRL");
  }

  // FTDI: drops the two status bytes that open every max-packet-size chunk of an IN transfer.
  std::size_t strip_ftdi_status(unsigned char* data, int transferred) const {
    std::size_t out = 0;
    for (int at = 0; at < transferred; at += ep_.in_packet) {
      const int end = std::min(transferred, at + ep_.in_packet);
      for (int i = at + kFtdiStatusBytes; i < end; ++i) data[out++] = data[i];
    }
    return out;
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
      std::size_t got = static_cast<std::size_t>(std::max(transferred, 0));
      if (bridge_ == UsbBridge::Ftdi) got = strip_ftdi_status(buffer.data(), transferred);
      if (got > 0)
        lines_.append(std::string_view(reinterpret_cast<const char*>(buffer.data()), got));
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
  UsbBridge bridge_;
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

UsbBridge usb_bridge_of(std::uint16_t vid, std::uint16_t pid) {
  if (vid == 0x1a86 && (pid == 0x7523 || pid == 0x7522 || pid == 0x5523)) return UsbBridge::Ch34x;
  if (vid == 0x0403 && (pid == 0x6001 || pid == 0x6014 || pid == 0x6015)) return UsbBridge::Ftdi;
  return UsbBridge::CdcAcm;
}

std::uint16_t ch34x_baud_register(int baud) {
  if (baud < 50 || baud > 2000000)
    throw InvalidInputError("baud rate " + std::to_string(baud) +
                            " is outside what a CH34x can do (50..2000000)");
  // rate = 48 MHz / (2^(12 - 3 ps - fact) * div), ps 0..3, fact 0..1, div 2..255: the closest.
  long best_error = -1;
  std::uint16_t best = 0;
  for (int ps = 0; ps <= 3; ++ps)
    for (int fact = 0; fact <= 1; ++fact) {
      const long clock = 48000000L >> (12 - 3 * ps - fact);
      for (long div = 2; div <= 255; ++div) {
        const long error = std::labs(clock / div - baud);
        if (best_error >= 0 && error >= best_error) continue;
        best_error = error;
        best = static_cast<std::uint16_t>(((0x100 - div) << 8) | (fact << 2) | ps);
      }
    }
  return best;
}

std::uint32_t ftdi_baud_divisor(int baud) {
  if (baud < 183 || baud > 3000000)
    throw InvalidInputError("baud rate " + std::to_string(baud) +
                            " is outside what an FT232 can do (183..3000000)");
  // 3 MHz / (n + f/8): n in the low 14 bits, the eighths f coded in 3 bits (14, 15 and 16).
  static constexpr std::uint32_t kEighthsCode[8] = {0, 3, 2, 4, 1, 5, 6, 7};
  const long eighths = (24000000L + baud / 2) / baud;
  const std::uint32_t whole = static_cast<std::uint32_t>(eighths >> 3);
  if (whole == 1 && (eighths & 7) == 0) return 0;  // 3 Mbaud is coded 0
  if (whole == 1 && (eighths & 7) == 4) return 1;  // 2 Mbaud is coded 1
  return whole | (kEighthsCode[eighths & 7] << 14);
}

std::optional<std::string> known_board_kind(std::uint16_t vid, std::uint16_t pid,
                                            std::uint8_t device_class, bool has_cdc_interface) {
  if (usb_bridge_of(vid, pid) == UsbBridge::Ch34x) return "CH340";
  if (usb_bridge_of(vid, pid) == UsbBridge::Ftdi) return "FTDI";
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
  auto transport = std::make_unique<UsbTransport>(ctx, handle, name, ep,
                                                  usb_bridge_of(desc.idVendor, desc.idProduct));
  transport->claim(options.baud);
  return transport;
}

}  // namespace scanmesh::drivers
