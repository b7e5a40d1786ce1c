// Every URI the program takes from outside: the flight link (--link, link.uri), the virtual
// sensor's device URI, and the query options both share. Each gives options or a refusal
// (LinkError, false); nothing opens a device or a socket here.
#include <cstdint>
#include <string>

#include "../../src/sensor/virtual_sensor/virtual_sensor_uri.hpp"
#include "fuzz_input.hpp"
#include "rgbd_odometry/core/uri_query.hpp"
#include "rgbd_odometry/link/transport.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace rgbdo;
  const std::string text(fuzz::text_of(data, size));
  try {
    const LinkOptions o = parse_link_uri(text);
    (void)o;
  } catch (const LinkError&) {
  }
  for (const std::string prefix : {"", "rgbdo-virtual:", "rgbdo-virtual:/tmp/x?"}) {
    virtual_sensor::Options o;
    (void)virtual_sensor::parse_uri(prefix + text, o);
  }
  std::size_t pairs = 0;
  (void)for_each_query_pair(text, [&](std::string_view, std::string_view) { ++pairs; });
  return 0;
}
