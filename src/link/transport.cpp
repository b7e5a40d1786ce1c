// Link URIs, the factory that opens the transport a URI names, and the serial capacity check.
// The transports themselves are in transport_udp.cpp and transport_serial.cpp.
#include "rgbd_odometry/link/transport.hpp"

#include "rgbd_odometry/core/uri_query.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <string_view>

namespace rgbdo {
namespace {

constexpr std::string_view kUriForms = "udp://HOST:PORT, udpin://[ADDRESS]:PORT or serial:///dev/DEVICE[:BAUD]";
// Bounds the queue's up-front allocation; 4096 frames is over two minutes at 30 Hz.
constexpr long long kMaxQueueFrames = 4096;

[[noreturn]] void fail(const std::string& uri, const std::string& problem) {
  throw LinkError("link '" + uri + "': " + problem);
}

bool all_digits(std::string_view s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// A non-negative decimal integer, or LinkError naming `what` ("port", "baud"...).
long long parse_count(const std::string& uri, std::string_view what, std::string_view text) {
  if (text.empty()) fail(uri, "missing " + std::string(what));
  long long value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (!all_digits(text) || end != text.data() + text.size())
    fail(uri, std::string(what) + " '" + std::string(text) + "' is not a number");
  if (ec == std::errc::result_out_of_range) fail(uri, std::string(what) + " '" + std::string(text) + "' is out of range");
  return value;
}

std::uint16_t parse_port(const std::string& uri, std::string_view what, std::string_view text, bool zero_allowed) {
  const long long port = parse_count(uri, what, text);
  const long long low = zero_allowed ? 0 : 1;
  if (port < low || port > 65535)
    fail(uri, std::string(what) + " " + std::string(text) + " out of range " + std::to_string(low) + "-65535");
  return static_cast<std::uint16_t>(port);
}

// Every option of the query, or LinkError naming a malformed one.
template <typename OnPair>
void for_each_option(const std::string& uri, std::string_view query, OnPair on_pair) {
  if (const auto bad = for_each_query_pair(query, on_pair))
    fail(uri, "option '" + std::string(*bad) + "' needs a value (KEY=VALUE)");
}

// SCHEME://[ADDRESS]:PORT: `host` gets the address without its brackets; returns the port's text.
std::string_view split_bracketed(const std::string& uri, std::string_view rest, const char* scheme, std::string& host) {
  const auto close = rest.find(']');
  if (close == std::string_view::npos) fail(uri, "IPv6 address without its closing ']'");
  host = std::string(rest.substr(1, close - 1));
  const std::string_view after = rest.substr(close + 1);
  if (after.empty() || after.front() != ':') fail(uri, "missing port (expected " + std::string(scheme) + "://[ADDRESS]:PORT)");
  return after.substr(1);
}

UdpLinkOptions parse_udp(const std::string& uri, std::string_view rest, std::string_view query) {
  UdpLinkOptions o;
  std::string_view port_text;
  if (rest.empty()) fail(uri, "missing host and port (expected udp://HOST:PORT)");
  if (rest.front() == '[') {  // udp://[::1]:14550
    port_text = split_bracketed(uri, rest, "udp", o.host);
  } else {
    const auto colon = rest.find(':');
    if (colon == std::string_view::npos) fail(uri, "missing port (expected udp://HOST:PORT)");
    if (rest.find(':', colon + 1) != std::string_view::npos)
      fail(uri, "an IPv6 address needs brackets: udp://[ADDRESS]:PORT");
    o.host = std::string(rest.substr(0, colon));
    port_text = rest.substr(colon + 1);
  }
  if (o.host.empty()) fail(uri, "missing host (expected udp://HOST:PORT)");
  if (port_text.empty()) fail(uri, "missing port (expected udp://HOST:PORT)");
  o.port = parse_port(uri, "port", port_text, false);
  for_each_option(uri, query, [&](std::string_view key, std::string_view value) {
    if (key == "local_port")
      o.local_port = parse_port(uri, "local_port", value, true);
    else
      fail(uri, "unknown udp option '" + std::string(key) + "' (known: local_port)");
  });
  return o;
}

// udpin://[ADDRESS]:PORT: the address to listen on may be left out (any IPv4 address).
UdpLinkOptions parse_udpin(const std::string& uri, std::string_view rest, std::string_view query) {
  UdpLinkOptions o;
  o.listen = true;
  std::string_view port_text;
  if (rest.empty()) fail(uri, "missing port (expected udpin://[ADDRESS]:PORT, e.g. udpin://:14540)");
  if (rest.front() == '[') {  // udpin://[::]:14540
    port_text = split_bracketed(uri, rest, "udpin", o.host);
    if (o.host.empty()) fail(uri, "empty IPv6 address (udpin://[::]:PORT listens on all)");
  } else {
    const auto colon = rest.rfind(':');
    if (colon == std::string_view::npos) fail(uri, "missing port (expected udpin://[ADDRESS]:PORT, e.g. udpin://:14540)");
    if (rest.find(':') != colon) fail(uri, "an IPv6 address needs brackets: udpin://[ADDRESS]:PORT");
    o.host = std::string(rest.substr(0, colon));
    port_text = rest.substr(colon + 1);
  }
  if (port_text.empty()) fail(uri, "missing port (expected udpin://[ADDRESS]:PORT)");
  o.port = parse_port(uri, "port", port_text, false);
  for_each_option(uri, query, [&](std::string_view key, std::string_view) {
    fail(uri, "unknown udpin option '" + std::string(key) + "' (udpin takes none)");
  });
  return o;
}

SerialLinkOptions parse_serial(const std::string& uri, std::string_view rest, std::string_view query) {
  SerialLinkOptions o;
  if (rest.empty()) fail(uri, "missing device path (expected serial:///dev/DEVICE[:BAUD])");
  if (rest.front() != '/')
    fail(uri, "device path '" + std::string(rest) + "' is not absolute (three slashes: serial:///dev/DEVICE)");
  // The baud is a trailing ":DIGITS" in the last path component. Other colons belong to the
  // path: /dev/serial/by-path/ names contain them (pci-0000:00:14.0-usb-0:2:1.0-port0).
  const auto last_slash = rest.rfind('/');
  const auto colon = rest.rfind(':');
  std::string_view path = rest;
  if (colon != std::string_view::npos && colon > last_slash) {
    const std::string_view baud_text = rest.substr(colon + 1);
    if (baud_text.empty()) fail(uri, "missing baud after ':'");
    if (all_digits(baud_text)) {
      const long long baud = parse_count(uri, "baud", baud_text);
      if (baud > 1'000'000'000) fail(uri, "unsupported baud " + std::string(baud_text));
      o.baud = static_cast<int>(baud);
      path = rest.substr(0, colon);
    }
  }
  if (path.size() <= 1 || path.back() == '/') fail(uri, "device path '" + std::string(path) + "' names a directory");
  o.device_path = std::string(path);
  try {
    check_serial_baud(o.baud);
  } catch (const LinkError& e) {
    fail(uri, e.what());
  }
  for_each_option(uri, query, [&](std::string_view key, std::string_view value) {
    if (key == "queue_frames") {
      const long long n = parse_count(uri, "queue_frames", value);
      if (n < 1 || n > kMaxQueueFrames)
        fail(uri, "queue_frames " + std::string(value) + " out of range 1-" + std::to_string(kMaxQueueFrames));
      o.queue_frames = static_cast<std::size_t>(n);
    } else {
      fail(uri, "unknown serial option '" + std::string(key) + "' (known: queue_frames)");
    }
  });
  return o;
}

std::string format_number(double value, int decimals) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  return buffer;
}

}  // namespace

void check_serial_baud(int baud) {
  if (std::find(kSupportedSerialBauds.begin(), kSupportedSerialBauds.end(), baud) != kSupportedSerialBauds.end())
    return;
  std::string supported;
  for (const int b : kSupportedSerialBauds) supported += (supported.empty() ? "" : ", ") + std::to_string(b);
  throw LinkError("unsupported baud " + std::to_string(baud) + " (supported: " + supported + ")");
}

LinkOptions parse_link_uri(const std::string& uri) {
  const auto sep = uri.find("://");
  if (sep == std::string::npos) fail(uri, "not a link URI (expected " + std::string(kUriForms) + ")");
  std::string scheme = uri.substr(0, sep);
  std::transform(scheme.begin(), scheme.end(), scheme.begin(), [](unsigned char c) { return std::tolower(c); });
  std::string_view rest = std::string_view(uri).substr(sep + 3);
  std::string_view query;
  if (const auto q = rest.find('?'); q != std::string_view::npos) {
    query = rest.substr(q + 1);
    rest = rest.substr(0, q);
  }
  if (scheme == "udp") return parse_udp(uri, rest, query);
  if (scheme == "udpin") return parse_udpin(uri, rest, query);
  if (scheme == "serial") return parse_serial(uri, rest, query);
  fail(uri, "unknown scheme '" + scheme + "' (expected " + std::string(kUriForms) + ")");
}

std::unique_ptr<OutputLink> open_link(const LinkOptions& options) {
  if (const auto* udp = std::get_if<UdpLinkOptions>(&options)) return open_udp_link(*udp);
  return open_serial_link(std::get<SerialLinkOptions>(options));
}

std::unique_ptr<OutputLink> open_link(const std::string& uri) { return open_link(parse_link_uri(uri)); }

SerialCapacity serial_capacity(int baud, std::size_t bytes_per_message, double messages_per_s) {
  if (baud <= 0) throw LinkError("serial capacity: baud " + std::to_string(baud) + " is not positive");
  if (!(messages_per_s >= 0) || !std::isfinite(messages_per_s))
    throw LinkError("serial capacity: message rate " + format_number(messages_per_s, 1) + " Hz is not valid");
  constexpr double kBitsPerByte8N1 = 10;  // start bit + 8 data bits + stop bit
  SerialCapacity c;
  c.bits_per_s_needed = static_cast<double>(bytes_per_message) * messages_per_s * kBitsPerByte8N1;
  c.utilisation = c.bits_per_s_needed / baud;
  c.verdict = c.utilisation > 1                         ? CapacityVerdict::Exceeded
              : c.utilisation > kSerialUtilisationWarning ? CapacityVerdict::NearLimit
                                                          : CapacityVerdict::Ok;
  c.message = std::to_string(baud) + " baud: " + std::to_string(bytes_per_message) + "-byte messages at " +
              format_number(messages_per_s, 1) + " Hz need " + format_number(c.bits_per_s_needed, 0) +
              " bit/s (8N1), " + format_number(100 * c.utilisation, 0) + "% of the line";
  switch (c.verdict) {
    case CapacityVerdict::Ok: c.message += ": ok"; break;
    case CapacityVerdict::NearLimit:
      c.message += ": above " + format_number(100 * kSerialUtilisationWarning, 0) +
                   "%, little slack for other traffic; consider a faster baud";
      break;
    case CapacityVerdict::Exceeded:
      c.message += ": more than the line carries, frames will be dropped; use a faster baud or a lower rate";
      break;
  }
  return c;
}

}  // namespace rgbdo
