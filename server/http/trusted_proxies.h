// --trusted-proxies (decision 86): the proxies whose X-Forwarded-For the server believes, and
// the client address a request is from. A value of the configuration (config.h parses it once,
// so a bad list stops the server at startup); the job routes' shares (share_of) and the access
// log ask it. The per-connection caps never do: they count sockets, before any header.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace mdn::http {

class TrustedProxies {
 public:
  // At most this many X-Forwarded-For entries are walked, from the right; the walk stops at
  // the last one and takes it (the gate's header limits bound the header anyway).
  static constexpr int kMaxEntriesWalked = 32;

  TrustedProxies() = default;  // none: X-Forwarded-For is never read
  // A comma-separated list of IPv4/IPv6 CIDRs ("10.0.0.0/8,::1/128"; a bare address is a /32 or
  // a /128; spaces around entries are allowed; IPv4-mapped IPv6 ranges match IPv4 addresses).
  // Throws std::invalid_argument naming the first bad entry. "" gives none.
  static TrustedProxies parse(const std::string& list);

  bool empty() const { return ranges_.empty(); }
  const std::string& text() const { return text_; }  // the list as given
  // True when `address` (IPv4, IPv6 or IPv4-mapped IPv6 text) lies in a range; false for
  // anything unparsable.
  bool contains(std::string_view address) const;

  // The client a request from the socket peer `peer` is from. An untrusted peer is the client
  // (its X-Forwarded-For is ignored: any client can write one). From a trusted peer: the
  // rightmost entry of the X-Forwarded-For lines (joined in order) that is not trusted, as
  // nginx's real_ip_recursive and Apache's mod_remoteip take it; the leftmost when all are
  // trusted; a malformed entry (a port, "unknown", an empty one) ends the walk at the last
  // good address, and so does the kMaxEntriesWalked-th. An address taken from the header is
  // in its canonical form (IPv4-mapped IPv6 as IPv4), so one client is one string.
  std::string client_address(const std::string& peer, const std::vector<std::string_view>& forwarded_for) const;

  // The same over a request's header multimap (ours or cpp-httplib's): its X-Forwarded-For lines.
  template <class Headers>
  std::string client_address_of(const std::string& peer, const Headers& headers) const {
    if (!contains(peer)) return peer;
    std::vector<std::string_view> lines;
    const auto [first, last] = headers.equal_range("X-Forwarded-For");
    for (auto it = first; it != last; ++it) lines.emplace_back(it->second);
    return client_address(peer, lines);
  }

 private:
  struct Range {
    std::array<std::uint8_t, 16> address{};  // IPv6; IPv4 as ::ffff:a.b.c.d
    int prefix = 0;                            // bits, [0, 128]
  };
  std::vector<Range> ranges_;
  std::string text_;
};

}  // namespace mdn::http
