// Link URIs (src/link/transport.cpp): every accepted form, and each malformed one rejected with a message
// that names the URI and the problem; the serial capacity check.
#include <gtest/gtest.h>

#include <string>
#include <variant>

#include "rgbd_odometry/link/transport.hpp"

namespace rgbdo {
namespace {

UdpLinkOptions udp(const std::string& uri) {
  const LinkOptions o = parse_link_uri(uri);
  EXPECT_TRUE(std::holds_alternative<UdpLinkOptions>(o)) << uri;
  return std::holds_alternative<UdpLinkOptions>(o) ? std::get<UdpLinkOptions>(o) : UdpLinkOptions{};
}

SerialLinkOptions serial(const std::string& uri) {
  const LinkOptions o = parse_link_uri(uri);
  EXPECT_TRUE(std::holds_alternative<SerialLinkOptions>(o)) << uri;
  return std::holds_alternative<SerialLinkOptions>(o) ? std::get<SerialLinkOptions>(o) : SerialLinkOptions{};
}

// The LinkError message for a URI, or "" if it was accepted.
std::string rejection(const std::string& uri) {
  try {
    parse_link_uri(uri);
  } catch (const LinkError& e) {
    return e.what();
  }
  return "";
}

TEST(LinkUri, UdpWithIpv4HostnameAndIpv6) {
  const UdpLinkOptions v4 = udp("udp://192.168.2.1:14550");
  EXPECT_EQ(v4.host, "192.168.2.1");
  EXPECT_EQ(v4.port, 14550);
  EXPECT_EQ(v4.local_port, 0);

  const UdpLinkOptions name = udp("udp://flight-computer.local:14540");
  EXPECT_EQ(name.host, "flight-computer.local");
  EXPECT_EQ(name.port, 14540);

  const UdpLinkOptions v6 = udp("udp://[::1]:14550");
  EXPECT_EQ(v6.host, "::1");
  EXPECT_EQ(v6.port, 14550);

  EXPECT_EQ(udp("udp://10.0.0.2:65535").port, 65535);
  EXPECT_EQ(udp("UDP://10.0.0.2:1").port, 1);  // the scheme is case-insensitive
}

TEST(LinkUri, UdpLocalPortOption) {
  const UdpLinkOptions o = udp("udp://10.0.0.2:14550?local_port=14551");
  EXPECT_EQ(o.port, 14550);
  EXPECT_EQ(o.local_port, 14551);
  EXPECT_EQ(udp("udp://10.0.0.2:14550?local_port=0").local_port, 0);
}

TEST(LinkUri, UdpInListensOnAnAddressOrAll) {
  const UdpLinkOptions any = udp("udpin://:14540");
  EXPECT_TRUE(any.listen);
  EXPECT_EQ(any.host, "");
  EXPECT_EQ(any.port, 14540);
  const UdpLinkOptions v4 = udp("udpin://0.0.0.0:14540");
  EXPECT_TRUE(v4.listen);
  EXPECT_EQ(v4.host, "0.0.0.0");
  const UdpLinkOptions v6 = udp("udpin://[::]:14540");
  EXPECT_TRUE(v6.listen);
  EXPECT_EQ(v6.host, "::");
  EXPECT_EQ(v6.port, 14540);
  EXPECT_FALSE(udp("udp://10.0.0.2:14550").listen);
}

TEST(LinkUri, UdpInMistakesAreNamed) {
  EXPECT_NE(rejection("udpin://").find("missing port"), std::string::npos);
  EXPECT_NE(rejection("udpin://:").find("missing port"), std::string::npos);
  EXPECT_NE(rejection("udpin://:0").find("out of range"), std::string::npos);
  EXPECT_NE(rejection("udpin://::1:14540").find("brackets"), std::string::npos);
  EXPECT_NE(rejection("udpin://[::1:14540").find("closing"), std::string::npos);
  EXPECT_NE(rejection("udpin://:14540?local_port=1").find("unknown udpin option"), std::string::npos);
  EXPECT_NE(rejection("tcp://x:1").find("udpin://"), std::string::npos) << "the forms are listed";
}

TEST(LinkUri, SerialPathAndBaud) {
  const SerialLinkOptions defaults = serial("serial:///dev/ttyUSB0");
  EXPECT_EQ(defaults.device_path, "/dev/ttyUSB0");
  EXPECT_EQ(defaults.baud, 921600);
  EXPECT_EQ(defaults.queue_frames, 64u);

  const SerialLinkOptions slow = serial("serial:///dev/ttyAMA0:57600");
  EXPECT_EQ(slow.device_path, "/dev/ttyAMA0");
  EXPECT_EQ(slow.baud, 57600);

  EXPECT_EQ(serial("serial:///dev/ttyACM0?queue_frames=8").queue_frames, 8u);
  EXPECT_EQ(serial("serial:///dev/ttyACM0:115200?queue_frames=8").baud, 115200);
}

TEST(LinkUri, SerialPathWithColonsKeepsThemUnlessTheyEndInDigits) {
  const std::string by_path = "/dev/serial/by-path/pci-0000:00:14.0-usb-0:2:1.0-port0";
  EXPECT_EQ(serial("serial://" + by_path).device_path, by_path);
  EXPECT_EQ(serial("serial://" + by_path).baud, 921600);
  const SerialLinkOptions with_baud = serial("serial://" + by_path + ":115200");
  EXPECT_EQ(with_baud.device_path, by_path);
  EXPECT_EQ(with_baud.baud, 115200);
  // A colon in a directory name is not taken for the baud.
  EXPECT_EQ(serial("serial:///dev/odd:1/ttyS0").device_path, "/dev/odd:1/ttyS0");
}

TEST(LinkUri, EverySupportedBaudParses) {
  for (const int baud : kSupportedSerialBauds) {
    EXPECT_EQ(serial("serial:///dev/ttyS1:" + std::to_string(baud)).baud, baud);
    EXPECT_NO_THROW(check_serial_baud(baud));
  }
}

struct BadUri {
  const char* uri;
  const char* problem;  // a part of the message
};

class LinkUriRejects : public testing::TestWithParam<BadUri> {};

TEST_P(LinkUriRejects, WithAMessageNamingTheUriAndTheProblem) {
  const BadUri& bad = GetParam();
  const std::string message = rejection(bad.uri);
  ASSERT_FALSE(message.empty()) << bad.uri << " was accepted";
  EXPECT_NE(message.find(bad.problem), std::string::npos) << "message: " << message;
  EXPECT_NE(message.find(std::string("'") + bad.uri + "'"), std::string::npos) << "message: " << message;
}

INSTANTIATE_TEST_SUITE_P(
    EachBadForm, LinkUriRejects,
    testing::Values(BadUri{"", "not a link URI"}, BadUri{"/dev/ttyUSB0", "not a link URI"},
                    BadUri{"127.0.0.1:14550", "not a link URI"}, BadUri{"tcp://127.0.0.1:5760", "unknown scheme 'tcp'"},
                    BadUri{"udp://", "missing host and port"}, BadUri{"udp://127.0.0.1", "missing port"},
                    BadUri{"udp://127.0.0.1:", "missing port"}, BadUri{"udp://:14550", "missing host"},
                    BadUri{"udp://127.0.0.1:0", "out of range 1-65535"},
                    BadUri{"udp://127.0.0.1:65536", "out of range 1-65535"},
                    BadUri{"udp://127.0.0.1:99999999999999999999999", "out of range"},
                    BadUri{"udp://127.0.0.1:14x", "port '14x' is not a number"},
                    BadUri{"udp://127.0.0.1:-1", "is not a number"},
                    BadUri{"udp://127.0.0.1:14550/odometry", "is not a number"},
                    BadUri{"udp://::1:14550", "needs brackets"}, BadUri{"udp://[::1:14550", "closing ']'"},
                    BadUri{"udp://[::1]", "missing port"}, BadUri{"udp://[::1]14550", "missing port"},
                    BadUri{"udp://[]:14550", "missing host"},
                    BadUri{"udp://127.0.0.1:14550?bind=1", "unknown udp option 'bind'"},
                    BadUri{"udp://127.0.0.1:14550?local_port", "needs a value"},
                    BadUri{"udp://127.0.0.1:14550?local_port=70000", "out of range 0-65535"},
                    BadUri{"serial://", "missing device path"},
                    BadUri{"serial://dev/ttyUSB0", "not absolute (three slashes"},
                    BadUri{"serial:///dev/ttyUSB0:12345", "unsupported baud 12345"},
                    BadUri{"serial:///dev/ttyUSB0:9600", "unsupported baud 9600 (supported: 57600, 115200"},
                    BadUri{"serial:///dev/ttyUSB0:99999999999", "unsupported baud"},
                    BadUri{"serial:///dev/ttyUSB0:", "missing baud"}, BadUri{"serial:///dev/", "names a directory"},
                    BadUri{"serial:///", "names a directory"},
                    BadUri{"serial:///dev/ttyUSB0?queue_frames=0", "queue_frames 0 out of range"},
                    BadUri{"serial:///dev/ttyUSB0?speed=57600", "unknown serial option 'speed'"}));

TEST(SerialBaud, UnsupportedRateNamesTheSupportedOnes) {
  try {
    check_serial_baud(38400);
    FAIL() << "38400 accepted";
  } catch (const LinkError& e) {
    EXPECT_NE(std::string(e.what()).find("unsupported baud 38400 (supported: 57600, 115200, 230400"), std::string::npos)
        << e.what();
  }
}

// ODOMETRY (#331) in MAVLink 2: 232-byte payload + 12 bytes of header and checksum.
constexpr std::size_t kOdometryFrameBytes = 244;

TEST(SerialCapacity, OdometryAt30HzFits115200) {
  const SerialCapacity c = serial_capacity(115200, kOdometryFrameBytes, 30);
  EXPECT_DOUBLE_EQ(c.bits_per_s_needed, 244 * 30 * 10);  // 10 bits a byte on the wire (8N1)
  EXPECT_NEAR(c.utilisation, 73200.0 / 115200.0, 1e-12);
  EXPECT_EQ(c.verdict, CapacityVerdict::Ok);
  EXPECT_NE(c.message.find("73200 bit/s"), std::string::npos) << c.message;
  EXPECT_NE(c.message.find("64%"), std::string::npos) << c.message;
}

TEST(SerialCapacity, OdometryAt30HzExceeds57600) {
  const SerialCapacity c = serial_capacity(57600, kOdometryFrameBytes, 30);
  EXPECT_GT(c.utilisation, 1.0);
  EXPECT_EQ(c.verdict, CapacityVerdict::Exceeded);
  EXPECT_NE(c.message.find("dropped"), std::string::npos) << c.message;
}

TEST(SerialCapacity, WarnsAbove80Percent) {
  const SerialCapacity near = serial_capacity(115200, 330, 30);  // 99000 bit/s: 86%
  EXPECT_EQ(near.verdict, CapacityVerdict::NearLimit);
  EXPECT_NE(near.message.find("above 80%"), std::string::npos) << near.message;
  // 80% exactly is still fine; one byte a second more is not.
  EXPECT_EQ(serial_capacity(115200, 9216, 1).verdict, CapacityVerdict::Ok);
  EXPECT_EQ(serial_capacity(115200, 9217, 1).verdict, CapacityVerdict::NearLimit);
  EXPECT_EQ(serial_capacity(115200, 11520, 1).verdict, CapacityVerdict::NearLimit);  // 100%: fits, no slack
  EXPECT_EQ(serial_capacity(115200, 11521, 1).verdict, CapacityVerdict::Exceeded);
}

TEST(SerialCapacity, NoMessagesNeedNothingAndBadArgumentsThrow) {
  EXPECT_EQ(serial_capacity(921600, kOdometryFrameBytes, 0).utilisation, 0.0);
  EXPECT_THROW(serial_capacity(0, kOdometryFrameBytes, 30), LinkError);
  EXPECT_THROW(serial_capacity(115200, kOdometryFrameBytes, -1), LinkError);
}

}  // namespace
}  // namespace rgbdo
