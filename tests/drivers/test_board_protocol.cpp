// The Horus dialect: command spelling and reply classification.
#include <gtest/gtest.h>

#include "scanmesh/core/errors.h"
#include "scanmesh/drivers/usb_transport.h"

#include "scanmesh/drivers/board.h"

namespace scanmesh::drivers {
namespace {

TEST(HorusDialect, SpellsCommandsAsTheFirmwareExpects) {
  const auto d = make_horus_dialect();
  EXPECT_EQ(d->move(12.5), "G1 X12.5");
  EXPECT_EQ(d->move(-0.9), "G1 X-0.9");
  EXPECT_EQ(d->move(360), "G1 X360");
  EXPECT_EQ(d->set_feed_rate(200), "G1 F200");
  EXPECT_EQ(d->laser(0, true), "M71 T1");
  EXPECT_EQ(d->laser(1, false), "M70 T2");
  EXPECT_EQ(d->motor(true), "M17");
  EXPECT_EQ(d->motor(false), "M18");
  EXPECT_EQ(d->set_position(12.5), "G92 X12.5");
  EXPECT_EQ(d->absolute_mode(), "G90");
  EXPECT_EQ(d->relative_mode(), "G91");
}

TEST(HorusDialect, ClassifiesReplies) {
  EXPECT_EQ(parse_horus_reply("ok\r").kind, BoardReply::Kind::Ok);
  EXPECT_EQ(parse_horus_reply("  ok ").kind, BoardReply::Kind::Ok);
  EXPECT_EQ(parse_horus_reply("error: motor disabled").kind, BoardReply::Kind::Error);
  EXPECT_EQ(parse_horus_reply("o\x7f#k").kind, BoardReply::Kind::Other);
  EXPECT_EQ(parse_horus_reply("okay").kind, BoardReply::Kind::Other);
  const BoardReply b = parse_horus_reply("Horus 0.2 ['$' for help]");
  EXPECT_EQ(b.kind, BoardReply::Kind::Banner);
  EXPECT_EQ(b.version_major, 0);
  EXPECT_EQ(b.version_minor, 2);
  EXPECT_EQ(parse_horus_reply("Horus x.y").kind, BoardReply::Kind::Other);
  EXPECT_EQ(parse_horus_reply("Horus 12.").kind, BoardReply::Kind::Other);
}

TEST(HorusDialect, AcceptsOnlyKnownFirmwareVersions) {
  const auto d = make_horus_dialect();
  EXPECT_TRUE(d->version_supported(parse_horus_reply("Horus 0.1 ['$' for help]")));
  EXPECT_TRUE(d->version_supported(parse_horus_reply("Horus 0.2 ['$' for help]")));
  EXPECT_FALSE(d->version_supported(parse_horus_reply("Horus 1.0 ['$' for help]")));
  EXPECT_FALSE(d->version_supported(parse_horus_reply("Grbl 1.1h ['$' for help]")));
}

TEST(LineBuffer, SplitsChunksIntoLines) {
  LineBuffer b;
  b.append("o");
  EXPECT_FALSE(b.pop_line());
  b.append("k\r\nerr");
  EXPECT_EQ(*b.pop_line(), "ok");
  EXPECT_FALSE(b.pop_line());
  b.append("or: x\n\n");
  EXPECT_EQ(*b.pop_line(), "error: x");
  EXPECT_EQ(*b.pop_line(), "");
}

}  // namespace
TEST(UsbBoardSpec, VidPidAndBusAddressAreParsedAnythingElseRefused) {
  const drivers::UsbSerialOptions byId = drivers::parse_usb_board_spec("1a86:7523");
  EXPECT_EQ(byId.vendor_id, 0x1a86);
  EXPECT_EQ(byId.product_id, 0x7523);
  EXPECT_EQ(byId.bus, -1);
  const drivers::UsbSerialOptions byPort = drivers::parse_usb_board_spec("usb:3:17");
  EXPECT_EQ(byPort.bus, 3);
  EXPECT_EQ(byPort.address, 17);
  EXPECT_EQ(byPort.vendor_id, 0);
  for (const char* bad : {"", "1a86", "1a86:75231", "usb:3", "usb:300:1", "usb:1:2x", "ttyACM0", "zz:zz"})
    EXPECT_THROW(drivers::parse_usb_board_spec(bad), InvalidInputError) << bad;
}

}  // namespace scanmesh::drivers
