#pragma once
// MAVLink references for the tests, written from the protocol's description and independent
// of src/link/: a bit-serial CRC, the wire order and CRC_EXTRA computed from the XML field
// lists (as pymavlink's generator does), and a frame builder.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace rgbdo::mavlink_reference {

// CRC-16/MCRF4XX bit by bit: reflected polynomial 0x1021 (0x8408 reversed), init 0xFFFF.
inline std::uint16_t reference_crc(const std::uint8_t* bytes, std::size_t n, std::uint16_t crc = 0xFFFF) {
  for (std::size_t i = 0; i < n; ++i) {
    crc ^= bytes[i];
    for (int bit = 0; bit < 8; ++bit) crc = (crc & 1) ? static_cast<std::uint16_t>((crc >> 1) ^ 0x8408) : crc >> 1;
  }
  return crc;
}
inline std::uint16_t reference_crc(std::string_view s, std::uint16_t crc) {
  return reference_crc(reinterpret_cast<const std::uint8_t*>(s.data()), s.size(), crc);
}

// A message field as the XML declares it, in XML order.
struct XmlField {
  std::string_view type;  // element type as CRC_EXTRA spells it (uint8_t_mavlink_version -> uint8_t)
  std::string_view name;
  int array_length = 0;   // 0: not an array
  bool extension = false;
};

inline std::size_t element_size(std::string_view type) {
  if (type == "uint64_t" || type == "int64_t" || type == "double") return 8;
  if (type == "uint32_t" || type == "int32_t" || type == "float") return 4;
  if (type == "uint16_t" || type == "int16_t") return 2;
  return 1;
}

// MAVLink's wire order: base fields stable-sorted by element size, largest first; extension
// fields after them, in XML order.
inline std::vector<XmlField> wire_order(const std::vector<XmlField>& xml) {
  std::vector<XmlField> base, ext;
  for (const auto& f : xml) (f.extension ? ext : base).push_back(f);
  std::stable_sort(base.begin(), base.end(),
                   [](const XmlField& a, const XmlField& b) { return element_size(a.type) > element_size(b.type); });
  base.insert(base.end(), ext.begin(), ext.end());
  return base;
}

inline std::size_t wire_offset(const std::vector<XmlField>& xml, std::string_view name) {
  std::size_t offset = 0;
  for (const auto& f : wire_order(xml)) {
    if (f.name == name) return offset;
    offset += element_size(f.type) * static_cast<std::size_t>(std::max(1, f.array_length));
  }
  ADD_FAILURE() << "no field " << name;
  return 0;
}

inline std::size_t wire_length(const std::vector<XmlField>& xml, bool with_extensions) {
  std::size_t n = 0;
  for (const auto& f : xml)
    if (with_extensions || !f.extension) n += element_size(f.type) * static_cast<std::size_t>(std::max(1, f.array_length));
  return n;
}

// pymavlink's message_checksum(): name, then each base field's type and name in wire order,
// space-terminated, and an array's length as one byte; folded to 8 bits.
inline std::uint8_t derive_crc_extra(std::string_view message_name, const std::vector<XmlField>& xml) {
  std::uint16_t crc = reference_crc(std::string(message_name) + " ", 0xFFFF);
  for (const auto& f : wire_order(xml)) {
    if (f.extension) break;
    crc = reference_crc(std::string(f.type) + " ", crc);
    crc = reference_crc(std::string(f.name) + " ", crc);
    if (f.array_length > 0) {
      const auto len = static_cast<std::uint8_t>(f.array_length);
      crc = reference_crc(&len, 1, crc);
    }
  }
  return static_cast<std::uint8_t>((crc & 0xFF) ^ (crc >> 8));
}

// A whole frame as the protocol describes it, from a payload already trimmed as the sender
// wants (MAVLink 2) or whole (MAVLink 1). MAVLink 2: a signature (13 bytes) follows the
// checksum when incompat_flags has bit 0 set; its content is whatever the caller gives.
inline std::vector<std::uint8_t> build_frame(int version, std::uint32_t msgid, std::uint8_t crc_extra,
                                             const std::vector<std::uint8_t>& payload, std::uint8_t seq,
                                             std::uint8_t sysid, std::uint8_t compid, std::uint8_t incompat = 0,
                                             const std::vector<std::uint8_t>& signature = {}) {
  std::vector<std::uint8_t> f;
  if (version == 2) {
    f = {0xFD, static_cast<std::uint8_t>(payload.size()), incompat, 0, seq, sysid, compid,
         static_cast<std::uint8_t>(msgid), static_cast<std::uint8_t>(msgid >> 8), static_cast<std::uint8_t>(msgid >> 16)};
  } else {
    f = {0xFE, static_cast<std::uint8_t>(payload.size()), seq, sysid, compid, static_cast<std::uint8_t>(msgid)};
  }
  f.insert(f.end(), payload.begin(), payload.end());
  std::uint16_t crc = reference_crc(f.data() + 1, f.size() - 1);
  crc = reference_crc(&crc_extra, 1, crc);
  f.push_back(static_cast<std::uint8_t>(crc & 0xFF));
  f.push_back(static_cast<std::uint8_t>(crc >> 8));
  f.insert(f.end(), signature.begin(), signature.end());
  return f;
}

}  // namespace rgbdo::mavlink_reference
