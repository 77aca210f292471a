// usbdevfs emulation: libusb's Linux backend talks to /dev/bus/usb/BBB/DDD with ioctls; here
// they arrive (through umockdev's preload library) on umockdev's worker thread and are answered
// by the simulated board firmware. URB memory lives in the client; UMockdevIoctlData resolves it
// into local copies that umockdev writes back when the ioctl completes.
#include <linux/usbdevice_fs.h>
#include <sys/ioctl.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <thread>

#include "emulated_impl.h"

namespace scanmesh::sim {
namespace {

// The firmware's UART rate (Serial.begin(115200) on the Horus firmware) and the mismatch beyond
// which a UART receiver no longer frames bytes correctly.
constexpr double kFirmwareBaud = 115200, kBaudTolerance = 0.03;

const char* kernel_driver_of(EmulatedBridge b) {
  return b == EmulatedBridge::Ch34x ? "ch341" : b == EmulatedBridge::Ftdi ? "ftdi_sio" : "cdc_acm";
}

// Bytes across a UART whose two ends disagree on the rate: framing errors, wrong bits.
bool line_garbled(const UsbBoardEmulation& b) {
  if (b.bridge == EmulatedBridge::CdcAcm) return false;  // the line is the board's own USB
  return std::abs(b.state.line_coding_baud - kFirmwareBaud) > kBaudTolerance * kFirmwareBaud;
}
std::string garble(std::string bytes) {
  for (char& c : bytes) c = static_cast<char>(static_cast<unsigned char>(c) ^ 0xa5u);
  return bytes;
}

// The rate a CH34x runs at for a baud register value (inverse of the chip's divisor formula:
// 48 MHz / (2^(12 - 3 ps - fact) * div)), 0 for an invalid value.
double ch34x_rate(unsigned reg) {
  const unsigned ps = reg & 3, fact = (reg >> 2) & 1, div = 0x100 - ((reg >> 8) & 0xff);
  if (div < 2 || div > 255) return 0;
  return 48e6 / (static_cast<double>(1u << (12 - 3 * ps - fact)) * div);
}

// The rate an FT232R runs at for a SET_BAUD_RATE divisor: 3 MHz / (whole + eighths / 8).
double ftdi_rate(unsigned value, unsigned index) {
  const unsigned whole = value & 0x3fff;
  const unsigned code = ((value >> 14) & 3) | ((index & 1) << 2);
  static constexpr double kEighths[8] = {0, 4, 2, 1, 3, 5, 6, 7};  // code -> eighths
  if (whole == 0 && code == 0) return 3e6;
  if (whole == 1 && code == 0) return 2e6;
  const double d = whole + kEighths[code] / 8.0;
  return d < 2 ? 0 : 3e6 / d;
}

// A vendor control request to a CH34x or FTDI bridge. Returns false for a request the chip
// would stall. `data` is the data stage (IN: to be filled).
bool bridge_request(UsbBoardEmulation& b, std::uint8_t type, std::uint8_t req, unsigned value,
                    unsigned index, unsigned char* data, unsigned length) {
  if (b.bridge == EmulatedBridge::Ch34x) {
    if (type == 0xc0 && req == 0x5f && length >= 2) {  // READ_VERSION
      data[0] = 0x31;
      data[1] = 0x00;
      return true;
    }
    if (type != 0x40) return false;
    if (req == 0xa1) return true;  // SERIAL_INIT
    if (req == 0x9a && value == 0x1312) {
      b.state.line_coding_baud = ch34x_rate(index & 0xff7f);
      return b.state.line_coding_baud > 0;
    }
    if (req == 0x9a && value == 0x2518) {
      b.state.data_bits = (index & 0xc0) == 0xc0 ? 5 + static_cast<int>(index & 3) : 0;
      return true;
    }
    if (req == 0xa4) {  // MODEM_CTRL, lines active low
      b.state.dtr = (value & 0x20) == 0;
      return true;
    }
    return false;
  }
  if (b.bridge == EmulatedBridge::Ftdi) {
    if (type != 0x40) return false;
    switch (req) {
      case 0x00:  // RESET
        b.unread.clear();
        return true;
      case 0x01:  // MODEM_CTRL: bit 8 masks DTR (bit 0)
        if (value & 0x100) b.state.dtr = value & 1;
        return true;
      case 0x03:  // SET_BAUD_RATE
        b.state.line_coding_baud = ftdi_rate(value, index);
        return b.state.line_coding_baud > 0;
      case 0x04:  // SET_DATA: bits 0-7 data bits
        b.state.data_bits = static_cast<int>(value & 0xff);
        return true;
      default:
        return false;
    }
  }
  return false;
}

void complete(UMockdevIoctlClient* client, long result, int err) {
  umockdev_ioctl_client_complete(client, result, err);
}

// Hands a finished URB to the REAPURB caller: the reap argument is a `void**` in the client.
void hand_over(UMockdevIoctlClient* client, UMockdevIoctlData* arg, UMockdevIoctlData* urb) {
  UMockdevIoctlData* slot = umockdev_ioctl_data_resolve(arg, 0, sizeof(void*), nullptr);
  umockdev_ioctl_data_set_ptr(slot, 0, urb);
  umockdev_ioctl_data_unref(slot);
  umockdev_ioctl_data_unref(urb);
  complete(client, 0, 0);
}

usbdevfs_urb* urb_of(UMockdevIoctlData* d) { return reinterpret_cast<usbdevfs_urb*>(d->data); }

gboolean answer_get_capabilities(UMockdevIoctlClient* client, UMockdevIoctlData* arg) {
  UMockdevIoctlData* d = umockdev_ioctl_data_resolve(arg, 0, sizeof(std::uint32_t), nullptr);
  const std::uint32_t caps = USBDEVFS_CAP_BULK_CONTINUATION | USBDEVFS_CAP_NO_PACKET_SIZE_LIM |
                             USBDEVFS_CAP_REAP_AFTER_DISCONNECT | USBDEVFS_CAP_ZERO_PACKET;
  std::memcpy(d->data, &caps, sizeof caps);
  umockdev_ioctl_data_unref(d);
  complete(client, 0, 0);
  return TRUE;
}

gboolean answer_getdriver(const UsbBoardEmulation& board, UMockdevIoctlClient* client,
                          UMockdevIoctlData* arg) {
  UMockdevIoctlData* d = umockdev_ioctl_data_resolve(arg, 0, sizeof(usbdevfs_getdriver), nullptr);
  auto* g = reinterpret_cast<usbdevfs_getdriver*>(d->data);
  if (board.state.kernel_driver_detached) {
    umockdev_ioctl_data_unref(d);
    complete(client, -1, ENODATA);
  } else {
    std::snprintf(g->driver, sizeof g->driver, "%s", kernel_driver_of(board.bridge));
    umockdev_ioctl_data_unref(d);
    complete(client, 0, 0);
  }
  return TRUE;
}

// USBDEVFS_IOCTL forwards an ioctl to the interface's kernel driver; libusb sends DISCONNECT and
// CONNECT through it to detach and re-attach that driver.
gboolean answer_kernel_driver_ioctl(UsbBoardEmulation& board, UMockdevIoctlClient* client,
                                    UMockdevIoctlData* arg) {
  UMockdevIoctlData* d = umockdev_ioctl_data_resolve(arg, 0, sizeof(usbdevfs_ioctl), nullptr);
  const int code = reinterpret_cast<usbdevfs_ioctl*>(d->data)->ioctl_code;
  umockdev_ioctl_data_unref(d);
  if (code == static_cast<int>(USBDEVFS_DISCONNECT)) board.state.kernel_driver_detached = true;
  if (code == static_cast<int>(USBDEVFS_CONNECT)) board.state.kernel_driver_detached = false;
  complete(client, 0, 0);
  return TRUE;
}

gboolean answer_claim_interface(UsbBoardEmulation& board, UMockdevIoctlClient* client, bool gone) {
  if (gone) return complete(client, -1, ENODEV), TRUE;
  if (!board.state.kernel_driver_detached) return complete(client, -1, EBUSY), TRUE;
  ++board.state.claimed_interfaces;
  complete(client, 0, 0);
  return TRUE;
}

gboolean answer_release_interface(UsbBoardEmulation& board, UMockdevIoctlClient* client) {
  --board.state.claimed_interfaces;
  complete(client, 0, 0);
  return TRUE;
}

gboolean answer_clear_halt(UsbBoardEmulation& board, UMockdevIoctlClient* client) {
  ++board.state.stalls_cleared;
  complete(client, 0, 0);
  return TRUE;
}

// A control transfer: `buffer` holds the 8-byte setup packet, then the data stage. Sets the URB's
// status and actual length; a request the bridge chip would stall ends with -EPIPE.
void run_control_transfer(UsbBoardEmulation& board, usbdevfs_urb* urb, UMockdevIoctlData* buffer) {
  const auto* bytes = buffer->data;
  const std::uint8_t request_type = bytes[0], req = bytes[1];
  const unsigned value = bytes[2] | (bytes[3] << 8);
  const unsigned index = bytes[4] | (bytes[5] << 8);
  const unsigned length = bytes[6] | (bytes[7] << 8);
  if (board.bridge != EmulatedBridge::CdcAcm) {
    if (!bridge_request(board, request_type, req, value, index, buffer->data + 8,
                        std::min<unsigned>(length, urb->buffer_length - 8))) {
      urb->status = -EPIPE;
      urb->actual_length = 0;
      return;
    }
    ++board.state.vendor_requests;
  } else if (request_type == 0x21 && req == 0x20 && length >= 7) {  // SET_LINE_CODING
    board.state.line_coding_baud =
        bytes[8] | (bytes[9] << 8) | (bytes[10] << 16) | (bytes[11] << 24);
    board.state.data_bits = bytes[14];
  } else if (request_type == 0x21 && req == 0x22) {  // SET_CONTROL_LINE_STATE
    const bool dtr = value & 1;
    // An Arduino resets when DTR rises: the banner follows after the boot time.
    if (dtr && !board.state.dtr) {
      board.firmware->reset();
      board.unread.clear();
    }
    board.state.dtr = dtr;
  }
  urb->actual_length = static_cast<int>(length);
}

// A bulk OUT transfer: the bytes go to the firmware's serial input, garbled if the baud is off.
void send_to_firmware(UsbBoardEmulation& board, usbdevfs_urb* urb, const guint8* bytes) {
  std::string sent(reinterpret_cast<const char*>(bytes),
                   static_cast<std::size_t>(urb->buffer_length));
  board.firmware->receive(line_garbled(board) ? garble(sent) : sent);
  urb->actual_length = urb->buffer_length;
}

// Control and bulk OUT URBs are answered at once and wait in `done`; bulk IN URBs wait in
// `in_flight` for firmware output. The URB stays resolved until it is reaped.
gboolean answer_submiturb(UsbBoardEmulation& board, UMockdevIoctlClient* client,
                          UMockdevIoctlData* arg, bool gone) {
  if (gone) return complete(client, -1, ENODEV), TRUE;
  UMockdevIoctlData* urb_data = umockdev_ioctl_data_resolve(arg, 0, sizeof(usbdevfs_urb), nullptr);
  usbdevfs_urb* urb = urb_of(urb_data);
  UMockdevIoctlData* buffer = umockdev_ioctl_data_resolve(
      urb_data, offsetof(usbdevfs_urb, buffer), static_cast<gsize>(urb->buffer_length), nullptr);
  const auto* bytes = buffer->data;
  urb->status = 0;
  if (urb->type == USBDEVFS_URB_TYPE_CONTROL && urb->buffer_length >= 8) {
    run_control_transfer(board, urb, buffer);
    umockdev_ioctl_data_unref(buffer);
    board.done.push_back(urb_data);
  } else if (urb->type == USBDEVFS_URB_TYPE_BULK && urb->endpoint == board.ep_out) {
    send_to_firmware(board, urb, bytes);
    umockdev_ioctl_data_unref(buffer);
    board.done.push_back(urb_data);
  } else if (urb->type == USBDEVFS_URB_TYPE_BULK && urb->endpoint == board.ep_in) {
    umockdev_ioctl_data_unref(buffer);
    board.in_flight.push_back(urb_data);
  } else {
    umockdev_ioctl_data_unref(buffer);
    umockdev_ioctl_data_unref(urb_data);
    return complete(client, -1, EINVAL), TRUE;
  }
  complete(client, 0, 0);
  return TRUE;
}

gboolean answer_discardurb(UsbBoardEmulation& board, UMockdevIoctlClient* client,
                           UMockdevIoctlData* arg) {
  const auto client_urb = reinterpret_cast<gulong>(*reinterpret_cast<void**>(arg->data));
  for (auto it = board.in_flight.begin(); it != board.in_flight.end(); ++it) {
    if ((*it)->client_addr != client_urb) continue;
    urb_of(*it)->status = -ENOENT;
    urb_of(*it)->actual_length = 0;
    board.done.push_back(*it);
    board.in_flight.erase(it);
    return complete(client, 0, 0), TRUE;
  }
  complete(client, -1, EINVAL);
  return TRUE;
}

// Moves waiting firmware output (`unread`) into a bulk IN URB's buffer; returns the bytes written.
std::size_t fill_in_urb(UsbBoardEmulation& board, usbdevfs_urb* urb, bool ftdi) {
  // urb->buffer points at the local copy of the client buffer resolved at submit time.
  auto* out = static_cast<unsigned char*>(urb->buffer);
  const auto room = static_cast<std::size_t>(urb->buffer_length);
  std::size_t n = 0;
  if (ftdi) {
    // Packets of in_packet bytes, each headed by modem status (CTS|DSR) and line status
    // (transmitter empty); a short packet ends the transfer.
    const std::size_t payload = static_cast<std::size_t>(board.in_packet) - 2;
    while (n + 2 <= room) {
      const std::size_t k = std::min({payload, board.unread.size(), room - n - 2});
      out[n] = 0x31;
      out[n + 1] = 0x60;
      std::memcpy(out + n + 2, board.unread.data(), k);
      board.unread.erase(0, k);
      n += 2 + k;
      if (k < payload) break;
    }
  } else {
    n = std::min(board.unread.size(), room);
    std::memcpy(out, board.unread.data(), n);
    board.unread.erase(0, n);
  }
  return n;
}

// Hands over the oldest bulk IN URB if it has an answer: an error when the device is gone or the
// endpoint stalled, else the firmware's output. Returns false when there is nothing to give yet.
bool reap_in_flight(UsbBoardEmulation& board, UMockdevIoctlClient* client, UMockdevIoctlData* arg,
                    bool gone) {
  UMockdevIoctlData* urb_data = board.in_flight.front();
  usbdevfs_urb* urb = urb_of(urb_data);
  if (gone || board.firmware->stalled()) {
    // Unplugged: the host controller gives back every URB with -ENODEV
    // (libusb: LIBUSB_ERROR_NO_DEVICE). Stalled: the endpoint answers STALL (-EPIPE).
    urb->status = gone ? -ENODEV : -EPIPE;
    urb->actual_length = 0;
    board.in_flight.pop_front();
    hand_over(client, arg, urb_data);
    return true;
  }
  const std::string fresh = board.firmware->transmit();
  board.unread += line_garbled(board) ? garble(fresh) : fresh;
  const auto now = std::chrono::steady_clock::now();
  // An FT232R sends a status-only packet every latency period (16 ms) when idle.
  const bool ftdi = board.bridge == EmulatedBridge::Ftdi;
  const bool ftdi_idle_packet = ftdi && now - board.last_in_packet > std::chrono::milliseconds(16);
  if (!board.unread.empty() || ftdi_idle_packet) {
    const std::size_t n = fill_in_urb(board, urb, ftdi);
    board.last_in_packet = now;
    urb->actual_length = static_cast<int>(n);
    urb->status = 0;
    board.in_flight.pop_front();
    hand_over(client, arg, urb_data);
    return true;
  }
  return false;
}

// REAPURB and REAPURBNDELAY alike: a finished URB if there is one, else EAGAIN (ENODEV once the
// device is gone).
gboolean answer_reapurb(UsbBoardEmulation& board, UMockdevIoctlClient* client,
                        UMockdevIoctlData* arg, bool gone) {
  if (!board.done.empty()) {
    UMockdevIoctlData* urb = board.done.front();
    board.done.erase(board.done.begin());
    hand_over(client, arg, urb);
    return TRUE;
  }
  if (!board.in_flight.empty() && reap_in_flight(board, client, arg, gone)) return TRUE;
  // Nothing to reap. The usbfs node under umockdev is a socket that always polls writable,
  // so libusb asks again at once; a short pause keeps that loop from eating a core.
  std::this_thread::sleep_for(std::chrono::microseconds(50));
  complete(client, -1, gone ? ENODEV : EAGAIN);
  return TRUE;
}

// umockdev's handle-ioctl signal for the usbfs node, on umockdev's worker thread. FALSE (the
// default branch) tells umockdev the request was not handled here.
gboolean handle_usb_ioctl(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer user) {
  auto* board = static_cast<UsbBoardEmulation*>(user);
  std::lock_guard lock(board->mutex);
  const unsigned long request = umockdev_ioctl_client_get_request(client);
  UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(client);
  const bool gone = board->firmware->unplugged();

  switch (request) {
    case USBDEVFS_GET_CAPABILITIES:
      return answer_get_capabilities(client, arg);
    case USBDEVFS_GETDRIVER:
      return answer_getdriver(*board, client, arg);
    case USBDEVFS_IOCTL:
      return answer_kernel_driver_ioctl(*board, client, arg);
    case USBDEVFS_CLAIMINTERFACE:
      return answer_claim_interface(*board, client, gone);
    case USBDEVFS_RELEASEINTERFACE:
      return answer_release_interface(*board, client);
    case USBDEVFS_CLEAR_HALT:
      return answer_clear_halt(*board, client);
    case USBDEVFS_RESET:
    case USBDEVFS_RESETEP:
    case USBDEVFS_SETCONFIGURATION:
      complete(client, 0, 0);
      return TRUE;

    case USBDEVFS_SUBMITURB:
      return answer_submiturb(*board, client, arg, gone);
    case USBDEVFS_DISCARDURB:
      return answer_discardurb(*board, client, arg);
    case USBDEVFS_REAPURB:
    case USBDEVFS_REAPURBNDELAY:
      return answer_reapurb(*board, client, arg, gone);
    default:
      return FALSE;
  }
}

// The 18-byte device descriptor in hex: `head` (length, type, bcdUSB, class, subclass, protocol,
// packet size), VID and PID little-endian, then `tail` (bcdDevice, string indices, configurations).
std::string device_descriptor_hex(const char* head, std::uint16_t vid, std::uint16_t pid,
                                  const char* tail) {
  char ids[16];
  std::snprintf(ids, sizeof ids, "%02x%02x%02x%02x", vid & 0xff, vid >> 8, pid & 0xff, pid >> 8);
  return head + std::string(ids) + tail;
}

// Device descriptor + configuration: a minimal CDC-ACM device (USB 2.0, class 2), a CH340
// (vendor class, one interface, 32-byte bulk endpoints) or an FT232R (vendor interface, 64-byte
// bulk endpoints).
std::string descriptors_hex(EmulatedBridge bridge, std::uint16_t vid, std::uint16_t pid) {
  if (bridge == EmulatedBridge::Ch34x) {
    return device_descriptor_hex("12011001ff000008", vid, pid, "640200020001") +
           "090227000101008031"  // configuration: 39 bytes, 1 interface
           "0904000003ff010200"  // interface 0: vendor class, 3 endpoints
           "07058202200000"      // EP 0x82 bulk IN, 32 bytes
           "07050202200000"      // EP 0x02 bulk OUT, 32 bytes
           "07058103080001";     // EP 0x81 interrupt IN, 8 bytes
  }
  if (bridge == EmulatedBridge::Ftdi) {
    return device_descriptor_hex("1201000200000008", vid, pid, "000601020301") +
           "09022000010100a02d"  // configuration: 32 bytes, 1 interface
           "0904000002ffffff02"  // interface 0: vendor class, 2 endpoints
           "07058102400000"      // EP 0x81 bulk IN, 64 bytes
           "07050202400000";     // EP 0x02 bulk OUT, 64 bytes
  }
  return device_descriptor_hex("1201000202000040", vid, pid, "000101020301") +
         "09023000020100c032"  // configuration: 48 bytes, 2 interfaces, bus powered
         "090400000102020100"  // interface 0: CDC communication, ACM, AT commands
         "0705820308000a"      // EP 0x82 interrupt IN, 8 bytes, 10 ms
         "0904010002"
         "0a000000"         // interface 1: CDC data
         "07050402400000"   // EP 0x04 bulk OUT, 64 bytes
         "07058302400000";  // EP 0x83 bulk IN, 64 bytes
}

}  // namespace

bool in_umockdev_environment() {
  // umockdev_in_mock_environment() only turns true once a testbed exists (it looks at
  // $UMOCKDEV_DIR); what matters before that is whether the preload library is loaded.
  const char* preload = std::getenv("LD_PRELOAD");
  return preload && std::strstr(preload, "umockdev-preload") != nullptr;
}

EmulatedDevices::EmulatedDevices() : impl_(std::make_unique<Impl>()) {
  if (!in_umockdev_environment())
    throw std::runtime_error("emulated devices need umockdev-wrapper (see docs/testing.md)");
  impl_->testbed = umockdev_testbed_new();
}

EmulatedDevices::~EmulatedDevices() = default;

EmulatedDevices::Impl::~Impl() {
  for (auto& b : boards) {
    for (auto* d : b->done) umockdev_ioctl_data_unref(d);
    for (auto* d : b->in_flight) umockdev_ioctl_data_unref(d);
  }
  for (auto* c : cameras) destroy_camera_emulation(c);
  if (testbed) g_object_unref(testbed);
  for (auto& b : boards)
    if (b->handler) g_object_unref(b->handler);
}

void EmulatedDevices::add_usb_board(std::shared_ptr<SimBoardFirmware> firmware,
                                    std::uint16_t vendor_id, std::uint16_t product_id,
                                    int address) {
  auto board = std::make_unique<UsbBoardEmulation>();
  board->firmware = std::move(firmware);
  if (vendor_id == 0x1a86 &&
      (product_id == 0x7523 || product_id == 0x7522 || product_id == 0x5523)) {
    board->bridge = EmulatedBridge::Ch34x;
    board->ep_in = 0x82;
    board->ep_out = 0x02;
    board->in_packet = 32;
  } else if (vendor_id == 0x0403 &&
             (product_id == 0x6001 || product_id == 0x6014 || product_id == 0x6015)) {
    board->bridge = EmulatedBridge::Ftdi;
    board->ep_in = 0x81;
    board->ep_out = 0x02;
    board->in_packet = 64;
  }
  board->state.kernel_driver = kernel_driver_of(board->bridge);
  board->handler = umockdev_ioctl_base_new();
  g_signal_connect(board->handler, "handle-ioctl", G_CALLBACK(handle_usb_ioctl), board.get());
  char node[64], sys[64];
  std::snprintf(node, sizeof node, "/dev/bus/usb/001/%03d", address);
  std::snprintf(sys, sizeof sys, "/devices/pci0000:00/usb1/1-%d", address);
  GError* error = nullptr;
  if (!umockdev_testbed_attach_ioctl(impl_->testbed, node, board->handler, &error)) {
    const std::string msg = error ? error->message : "unknown";
    if (error) g_error_free(error);
    throw std::runtime_error("umockdev_testbed_attach_ioctl: " + msg);
  }
  char vidpid[32];
  std::snprintf(vidpid, sizeof vidpid, "%04x\\n\nA: idProduct=%04x\\n", vendor_id, product_id);
  const std::string description =
      std::string("P: ") + sys + "\nN: bus/usb/001/" + (node + std::strlen("/dev/bus/usb/001/")) +
      "\nE: SUBSYSTEM=usb\nE: DEVTYPE=usb_device\nE: DRIVER=usb\n"
      "E: BUSNUM=001\nE: DEVNUM=" +
      (node + std::strlen("/dev/bus/usb/001/")) + "\nE: DEVNAME=" + node +
      "\nA: busnum=1\\n\nA: devnum=" + std::to_string(address) +
      "\\n\nA: speed=12\\n\nA: bConfigurationValue=1\\n\nA: idVendor=" + vidpid +
      "\nH: descriptors=" + descriptors_hex(board->bridge, vendor_id, product_id) + "\n";
  if (!umockdev_testbed_add_from_string(impl_->testbed, description.c_str(), &error)) {
    const std::string msg = error ? error->message : "unknown";
    if (error) g_error_free(error);
    throw std::runtime_error("umockdev_testbed_add_from_string: " + msg);
  }
  impl_->boards.push_back(std::move(board));
}

EmulatedUsbBoardState EmulatedDevices::usb_board_state() const {
  if (impl_->boards.empty()) return {};
  std::lock_guard lock(impl_->boards.front()->mutex);
  return impl_->boards.front()->state;
}

}  // namespace scanmesh::sim
