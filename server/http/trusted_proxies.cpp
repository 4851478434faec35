#include "server/http/trusted_proxies.h"

#include <charconv>
#include <optional>
#include <stdexcept>

#include <arpa/inet.h>

namespace mdn::http {
namespace {

using Address = std::array<std::uint8_t, 16>;

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

bool is_mapped_ipv4(const Address& a) {
  for (int i = 0; i < 10; ++i)
    if (a[i] != 0) return false;
  return a[10] == 0xff && a[11] == 0xff;
}

// IPv4 dotted decimal or IPv6 text (inet_pton's forms; no port, brackets or zone), as IPv6 with
// IPv4 mapped; nullopt otherwise.
std::optional<Address> parse_address(std::string_view text) {
  if (text.empty() || text.size() > INET6_ADDRSTRLEN) return std::nullopt;
  const std::string s(text);  // inet_pton wants a terminated string
  Address a{};
  in_addr v4{};
  if (inet_pton(AF_INET, s.c_str(), &v4) == 1) {
    a[10] = a[11] = 0xff;
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(&v4.s_addr);  // network order
    for (int i = 0; i < 4; ++i) a[12 + i] = bytes[i];
    return a;
  }
  in6_addr v6{};
  if (inet_pton(AF_INET6, s.c_str(), &v6) == 1) {
    for (int i = 0; i < 16; ++i) a[i] = v6.s6_addr[i];
    return a;
  }
  return std::nullopt;
}

std::string canonical(const Address& a) {
  char out[INET6_ADDRSTRLEN] = {};
  if (is_mapped_ipv4(a)) {
    in_addr v4{};
    auto* bytes = reinterpret_cast<std::uint8_t*>(&v4.s_addr);
    for (int i = 0; i < 4; ++i) bytes[i] = a[12 + i];
    inet_ntop(AF_INET, &v4, out, sizeof out);
  } else {
    in6_addr v6{};
    for (int i = 0; i < 16; ++i) v6.s6_addr[i] = a[i];
    inet_ntop(AF_INET6, &v6, out, sizeof out);
  }
  return out;
}

bool prefix_matches(const Address& a, const Address& range, int prefix) {
  const int whole = prefix / 8, rest = prefix % 8;
  for (int i = 0; i < whole; ++i)
    if (a[i] != range[i]) return false;
  if (rest == 0) return true;
  const std::uint8_t mask = std::uint8_t(0xff << (8 - rest));
  return (a[whole] & mask) == (range[whole] & mask);
}

}  // namespace

TrustedProxies TrustedProxies::parse(const std::string& list) {
  TrustedProxies out;
  out.text_ = list;
  if (trim(list).empty()) return out;
  std::string_view rest = list;
  while (true) {
    const std::size_t comma = rest.find(',');
    const std::string_view entry = trim(rest.substr(0, comma));
    const std::size_t slash = entry.find('/');
    const auto address = parse_address(entry.substr(0, slash));
    const bool ipv4 = entry.substr(0, slash).find(':') == std::string_view::npos;
    const int max_prefix = ipv4 ? 32 : 128;
    int prefix = max_prefix;
    bool good = address.has_value();
    if (good && slash != std::string_view::npos) {
      const std::string_view bits = entry.substr(slash + 1);
      const auto [end, ec] = std::from_chars(bits.data(), bits.data() + bits.size(), prefix);
      good = ec == std::errc() && end == bits.data() + bits.size() && !bits.empty() && bits.size() <= 3 &&
             prefix >= 0 && prefix <= max_prefix;
    }
    if (!good)
      throw std::invalid_argument("'" + std::string(entry) + "' is not an IPv4 or IPv6 address or CIDR (e.g. 10.0.0.0/8, ::1/128)");
    Range range{*address, ipv4 ? prefix + 96 : prefix};
    for (int bit = range.prefix; bit < 128; ++bit)  // the host bits are not part of the range
      range.address[bit / 8] &= std::uint8_t(~(0x80 >> (bit % 8)));
    out.ranges_.push_back(range);
    if (comma == std::string_view::npos) break;
    rest.remove_prefix(comma + 1);
  }
  return out;
}

bool TrustedProxies::contains(std::string_view address) const {
  if (ranges_.empty()) return false;
  const auto a = parse_address(trim(address));
  if (!a) return false;
  for (const Range& r : ranges_)
    if (prefix_matches(*a, r.address, r.prefix)) return true;
  return false;
}

std::string TrustedProxies::client_address(const std::string& peer,
                                           const std::vector<std::string_view>& forwarded_for) const {
  if (!contains(peer)) return peer;
  std::string client = peer;  // the last good address of the walk
  int walked = 0;
  // From the right: the last line's last entry is the one the trusted peer itself appended.
  for (auto line = forwarded_for.rbegin(); line != forwarded_for.rend(); ++line) {
    std::string_view rest = *line;
    while (true) {
      const std::size_t comma = rest.rfind(',');
      const std::string_view entry = trim(comma == std::string_view::npos ? rest : rest.substr(comma + 1));
      const auto address = parse_address(entry);
      if (!address) return client;  // never trust an unparsable string
      client = canonical(*address);
      if (!contains(client) || ++walked == kMaxEntriesWalked) return client;
      if (comma == std::string_view::npos) break;
      rest = rest.substr(0, comma);
    }
  }
  return client;  // every entry trusted: the leftmost
}

}  // namespace mdn::http
