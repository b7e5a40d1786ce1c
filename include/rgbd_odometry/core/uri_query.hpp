#pragma once
// The "?KEY=VALUE&KEY=VALUE" tail of the URIs the program takes (link URIs, the virtual
// sensor's device URI): one parser for every URI, so that they all read options alike.
#include <optional>
#include <string_view>

namespace rgbdo {

// Calls on_pair(key, value) for each "KEY=VALUE" of `query` (the text after '?'), in order.
// Returns the first item that has no '=' (a malformed option), or nothing when all are well
// formed; the pairs before it have been visited.
template <typename OnPair>
std::optional<std::string_view> for_each_query_pair(std::string_view query, OnPair&& on_pair) {
  while (!query.empty()) {
    const auto amp = query.find('&');
    const std::string_view pair = query.substr(0, amp);
    const auto eq = pair.find('=');
    if (eq == std::string_view::npos) return pair;
    on_pair(pair.substr(0, eq), pair.substr(eq + 1));
    if (amp == std::string_view::npos) break;
    query.remove_prefix(amp + 1);
  }
  return std::nullopt;
}

}  // namespace rgbdo
