// JPEG through libjpeg (Debian's libjpeg-turbo), the codec OpenCV's imgcodecs wraps. Loading
// imgcodecs for it put ~120 more shared libraries (GDAL, GDCM, OpenEXR, HEIF, ...) into every
// process that links the drivers, the simulator or the acquisition: 80 ms per start of the
// CLI and of each test process. The encoder and decoder settings are OpenCV's
// (tests/core/test_jpeg_vs_opencv.cpp compares the bytes and pixels).
//
// libjpeg reports fatal errors through error_exit, which must not return: it longjmps back to
// the setjmp in decode_into / encode_into. Those functions hold no C++ object of their own
// that a jump could skip; what they fill belongs to the caller.
// jpeglib.h uses size_t and FILE without including their headers.
#include <cstddef>
#include <cstdio>
// (keep the order)
#include <jpeglib.h>

#include <csetjmp>
#include <cstdlib>
#include <memory>
#include <new>
#include <optional>
#include <string>
#include <utility>

#include "scanmesh/core/errors.h"
#include "scanmesh/core/image.h"

namespace scanmesh {

namespace {

// A picture larger than this is surely a hostile header (the PNG reader's bound), and so is
// a stream asking libjpeg for more working memory (a progressive JPEG keeps every coefficient:
// two bytes per sample, beyond the pixels) or for more scans than any encoder writes (each
// scan is a pass over the coefficients: a small file of thousands of scans takes minutes).
constexpr std::uint64_t kMaxJpegPixelBytes = 1ull << 30;
constexpr long kMaxJpegWorkingBytes = 1l << 30;
constexpr int kMaxJpegScans = 500;

struct ErrorManager {
  jpeg_error_mgr pub;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX] = "";
  bool ours = false;  // the message is one of this file's limits, not libjpeg's
};

// One of this file's refusals: the message (printf-style) and `ours` set.
template <typename... Args>
void refuse(ErrorManager& err, const char* format, Args... args) {
  std::snprintf(err.message, sizeof err.message, format, args...);
  err.ours = true;
}

[[noreturn]] void jump_on_error(j_common_ptr info) {
  auto* err = reinterpret_cast<ErrorManager*>(info->err);
  (*info->err->format_message)(info, err->message);
  std::longjmp(err->jump, 1);
}

// Warnings (corrupt data libjpeg recovered from) are not printed: a CLI's stderr is for its own
// messages, and the frame checks before decoding say what is wrong with a frame.
void stay_quiet(j_common_ptr) {}

void refuse_endless_scans(j_common_ptr info) {
  auto* d = reinterpret_cast<j_decompress_ptr>(info);
  if (d->is_decompressor && d->input_scan_number > kMaxJpegScans) {
    auto* err = reinterpret_cast<ErrorManager*>(info->err);
    refuse(*err, "has more than %d scans", kMaxJpegScans);
    std::longjmp(err->jump, 1);
  }
}

jpeg_error_mgr* install(ErrorManager& err) {
  jpeg_error_mgr* pub = jpeg_std_error(&err.pub);
  err.pub.error_exit = jump_on_error;
  err.pub.output_message = stay_quiet;
  return pub;
}

// False with err.message set when libjpeg gives up, the picture is too large or its header
// declares another size than `expected`.
bool decode_into(std::span<const std::uint8_t> bytes,
                 const std::optional<std::pair<int, int>>& expected, Image8& out,
                 ErrorManager& err) {
  jpeg_decompress_struct info;
  jpeg_progress_mgr progress{};
  progress.progress_monitor = refuse_endless_scans;
  info.err = install(err);
  if (setjmp(err.jump)) {
    jpeg_destroy_decompress(&info);
    return false;
  }
  jpeg_create_decompress(&info);
  info.mem->max_memory_to_use = kMaxJpegWorkingBytes;  // beyond it libjpeg gives up (no disk)
  info.progress = &progress;
  jpeg_mem_src(&info, bytes.data(), static_cast<unsigned long>(bytes.size()));
  jpeg_read_header(&info, TRUE);
  info.out_color_space = JCS_RGB;  // grey pictures are replicated, as OpenCV's IMREAD_COLOR
  jpeg_calc_output_dimensions(&info);
  const std::uint64_t pixel_bytes = std::uint64_t{info.output_width} * info.output_height * 3;
  bool refused = true;
  if (pixel_bytes == 0 || pixel_bytes > kMaxJpegPixelBytes)
    refuse(err, "declares an impossible size %u x %u", info.output_width, info.output_height);
  else if (expected && (info.output_width != static_cast<JDIMENSION>(expected->first) ||
                        info.output_height != static_cast<JDIMENSION>(expected->second)))
    refuse(err, "declares %ux%u, expected %dx%d", info.output_width, info.output_height,
           expected->first, expected->second);
  else
    try {
      out = Image8(static_cast<int>(info.output_width), static_cast<int>(info.output_height), 3);
      refused = false;
    } catch (const std::bad_alloc&) {
      refuse(err, "needs more memory than there is");
    }
  if (refused) {  // before any pixel is allocated or decoded
    jpeg_destroy_decompress(&info);
    return false;
  }
  jpeg_start_decompress(&info);
  while (info.output_scanline < info.output_height) {
    JSAMPROW row = out.at(0, static_cast<int>(info.output_scanline));
    jpeg_read_scanlines(&info, &row, 1);
  }
  jpeg_finish_decompress(&info);
  jpeg_destroy_decompress(&info);
  return true;
}

// libjpeg's memory destination: it allocates and grows `data` itself (freed by the caller).
struct EncodedBytes {
  unsigned char* data = nullptr;
  unsigned long size = 0;
};

bool encode_into(const Image8& rgb, int quality, EncodedBytes& out, ErrorManager& err) {
  jpeg_compress_struct info;
  info.err = install(err);
  if (setjmp(err.jump)) {
    jpeg_destroy_compress(&info);
    return false;
  }
  jpeg_create_compress(&info);
  jpeg_mem_dest(&info, &out.data, &out.size);
  info.image_width = static_cast<JDIMENSION>(rgb.width);
  info.image_height = static_cast<JDIMENSION>(rgb.height);
  info.input_components = 3;
  info.in_color_space = JCS_RGB;
  // libjpeg's defaults (baseline, 4:2:0, standard Huffman tables, JFIF header) at `quality`
  // with its baseline-compatible quantisation tables: what OpenCV's encoder writes.
  jpeg_set_defaults(&info);
  jpeg_set_quality(&info, quality, TRUE);
  jpeg_start_compress(&info, TRUE);
  while (info.next_scanline < info.image_height) {
    JSAMPROW row = const_cast<std::uint8_t*>(rgb.at(0, static_cast<int>(info.next_scanline)));
    jpeg_write_scanlines(&info, &row, 1);
  }
  jpeg_finish_compress(&info);
  jpeg_destroy_compress(&info);
  return true;
}

}  // namespace

Image8 decode_jpeg(std::span<const std::uint8_t> bytes, const std::filesystem::path& source,
                   const std::optional<std::pair<int, int>>& expected_size) {
  if (bytes.size() < 4 || bytes[0] != 0xff || bytes[1] != 0xd8)
    throw FileFormatError(source, "not a JPEG (no SOI marker)");
  Image8 out;
  ErrorManager err;
  if (!decode_into(bytes, expected_size, out, err))
    throw FileFormatError(source, std::string(err.ours ? "JPEG " : "JPEG does not decode: ") +
                                      err.message);
  return out;
}

std::vector<std::uint8_t> encode_jpeg(const Image8& rgb, int quality) {
  if (rgb.channels != 3 || rgb.width <= 0 || rgb.height <= 0 ||
      rgb.pixels.size() != static_cast<std::size_t>(rgb.width) * rgb.height * 3)
    throw InvalidInputError("encode_jpeg needs a non-empty RGB image");
  if (quality < 1 || quality > 100)
    throw InvalidInputError("JPEG quality " + std::to_string(quality) + " is not in 1..100");
  // JPEG's own bound on a side (libjpeg's JPEG_MAX_DIMENSION).
  if (rgb.width > 65500 || rgb.height > 65500)
    throw InvalidInputError("a JPEG cannot hold " + std::to_string(rgb.width) + " x " +
                            std::to_string(rgb.height) + " pixels (65,500 at most per side)");
  EncodedBytes encoded;
  ErrorManager err;
  const bool ok = encode_into(rgb, quality, encoded, err);
  const std::unique_ptr<unsigned char, decltype(&std::free)> owner(encoded.data, &std::free);
  if (!ok) throw IoError(std::string("JPEG encoding failed: ") + err.message);
  return {encoded.data, encoded.data + encoded.size};
}

Image8 decode_image(std::span<const std::uint8_t> bytes, const std::filesystem::path& source) {
  if (bytes.size() >= 3 && bytes[0] == 0xff && bytes[1] == 0xd8 && bytes[2] == 0xff)
    return decode_jpeg(bytes, source);
  return decode_png(bytes, source);
}

}  // namespace scanmesh
