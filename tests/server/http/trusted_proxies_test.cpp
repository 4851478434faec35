// --trusted-proxies (decision 86): the CIDR list, and the walk of X-Forwarded-For that finds the
// client behind a trusted proxy (the rightmost untrusted entry; spoofed entries to its left are
// never reached; a malformed entry or the 32nd ends the walk).
#include "server/http/trusted_proxies.h"

#include <gtest/gtest.h>

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "server/http/config.h"
#include "server/http/transport/http_message.h"
#include "parse_config.h"

namespace mdn::http {
namespace {

const TrustedProxies kPrivate = TrustedProxies::parse("10.0.0.0/8, 172.16.0.0/12,192.168.0.0/16,127.0.0.1/32,::1/128,fd00::/8");

std::string client(const TrustedProxies& p, const std::string& peer, std::vector<std::string_view> xff) {
  return p.client_address(peer, xff);
}

TEST(TrustedProxies, RangesContainTheirAddressesOnly) {
  EXPECT_TRUE(kPrivate.contains("10.255.0.1"));
  EXPECT_TRUE(kPrivate.contains("172.31.255.255"));
  EXPECT_FALSE(kPrivate.contains("172.32.0.0"));
  EXPECT_FALSE(kPrivate.contains("11.0.0.1"));
  EXPECT_TRUE(kPrivate.contains("127.0.0.1"));
  EXPECT_FALSE(kPrivate.contains("127.0.0.2"));  // a /32
  EXPECT_TRUE(kPrivate.contains("::1"));
  EXPECT_TRUE(kPrivate.contains("fdab::7"));
  EXPECT_FALSE(kPrivate.contains("2001:db8::1"));
  // An IPv4 peer on a dual-stack socket is IPv4-mapped; it is the same address.
  EXPECT_TRUE(kPrivate.contains("::ffff:10.1.2.3"));
  EXPECT_FALSE(kPrivate.contains("::ffff:8.8.8.8"));
  EXPECT_FALSE(kPrivate.contains("not an address"));
  EXPECT_FALSE(kPrivate.contains("10.0.0.1:80"));
  EXPECT_FALSE(kPrivate.contains(""));
  // Host bits of a range are ignored; a bare address is one host; /0 is everything.
  EXPECT_TRUE(TrustedProxies::parse("10.1.2.3/8").contains("10.200.0.1"));
  EXPECT_FALSE(TrustedProxies::parse("10.1.2.3").contains("10.1.2.4"));
  EXPECT_TRUE(TrustedProxies::parse("0.0.0.0/0").contains("203.0.113.9"));
  EXPECT_FALSE(TrustedProxies::parse("0.0.0.0/0").contains("2001:db8::1"));
  EXPECT_TRUE(TrustedProxies::parse("::ffff:10.0.0.0/104").contains("10.9.9.9"));
  EXPECT_TRUE(TrustedProxies::parse("2001:db8::/33").contains("2001:db8:7fff::1"));
  EXPECT_FALSE(TrustedProxies::parse("2001:db8::/33").contains("2001:db8:8000::1"));
  EXPECT_TRUE(TrustedProxies::parse("").empty());
  EXPECT_FALSE(TrustedProxies().contains("127.0.0.1"));
}

TEST(TrustedProxies, BadListsAreRefusedNamingTheEntry) {
  for (const char* bad : {"10.0.0.0/33", "::1/129", "10.0.0/8", "10.0.0.0/", "10.0.0.0/8x", "10.0.0.0/-1",
                          "localhost", "10.0.0.0/8,,::1", "10.0.0.0/8,", "[::1]/128", "10.0.0.1:80", "fe80::1%eth0"}) {
    try {
      TrustedProxies::parse(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("is not an IPv4 or IPv6"), std::string::npos) << bad << ": " << e.what();
    }
  }
  try {
    TrustedProxies::parse("10.0.0.0/8, 192.168.0.0/64 ,::1");
    ADD_FAILURE() << "accepted a /64 of IPv4";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'192.168.0.0/64'"), std::string::npos) << e.what();
  }
}

TEST(TrustedProxies, AnUntrustedPeerIsTheClientWhateverItsHeaderSays) {
  EXPECT_EQ(client(kPrivate, "203.0.113.7", {"10.0.0.1", "198.51.100.2"}), "203.0.113.7");
  EXPECT_EQ(client(TrustedProxies(), "127.0.0.1", {"198.51.100.2"}), "127.0.0.1");
  EXPECT_EQ(client(kPrivate, "127.0.0.1", {}), "127.0.0.1");  // a trusted peer without the header
}

TEST(TrustedProxies, TheClientIsTheRightmostUntrustedEntry) {
  // nginx appends the address it saw: a client's own (spoofed) entries stay to its left.
  EXPECT_EQ(client(kPrivate, "10.0.0.5", {"198.51.100.2"}), "198.51.100.2");
  EXPECT_EQ(client(kPrivate, "10.0.0.5", {"1.1.1.1, 2.2.2.2, 198.51.100.2"}), "198.51.100.2");
  // Through a chain of trusted proxies, each appending the one before it.
  EXPECT_EQ(client(kPrivate, "10.0.0.5", {"6.6.6.6, 198.51.100.2, 192.168.1.1,10.0.0.9"}), "198.51.100.2");
  // Several header lines are one list, in order.
  EXPECT_EQ(client(kPrivate, "10.0.0.5", {"6.6.6.6, 198.51.100.2", "192.168.1.1"}), "198.51.100.2");
  EXPECT_EQ(client(kPrivate, "10.0.0.5", {"6.6.6.6", "198.51.100.2"}), "198.51.100.2");
  // IPv6 and IPv4-mapped entries; the answer in canonical form (one client, one string).
  EXPECT_EQ(client(kPrivate, "::1", {"2001:DB8:0:0::1"}), "2001:db8::1");
  EXPECT_EQ(client(kPrivate, "::ffff:127.0.0.1", {"::ffff:198.51.100.2"}), "198.51.100.2");
  EXPECT_EQ(client(kPrivate, "127.0.0.1", {"  198.51.100.2\t"}), "198.51.100.2");
}

TEST(TrustedProxies, AllTrustedGivesTheLeftmost) {
  EXPECT_EQ(client(kPrivate, "10.0.0.5", {"192.168.0.3, 10.0.0.4"}), "192.168.0.3");
  EXPECT_EQ(client(kPrivate, "10.0.0.5", {"::1", "10.0.0.4"}), "::1");
}

TEST(TrustedProxies, AMalformedEntryEndsTheWalkAtTheLastGoodAddress) {
  // Never an unparsable string as the client: the last good one (here the peer itself).
  EXPECT_EQ(client(kPrivate, "10.0.0.5", {"unknown"}), "10.0.0.5");
  EXPECT_EQ(client(kPrivate, "10.0.0.5", {"198.51.100.2:4711"}), "10.0.0.5");
  EXPECT_EQ(client(kPrivate, "10.0.0.5", {""}), "10.0.0.5");
  // A malformed entry left of trusted ones: the leftmost trusted one walked.
  EXPECT_EQ(client(kPrivate, "10.0.0.5", {"198.51.100.2, garbage, 192.168.0.3, 10.0.0.4"}), "192.168.0.3");
  EXPECT_EQ(client(kPrivate, "10.0.0.5", {"198.51.100.2,,10.0.0.4"}), "10.0.0.4");
  // One to the right of the first untrusted entry is never reached.
  EXPECT_EQ(client(kPrivate, "10.0.0.5", {"garbage, 198.51.100.2"}), "198.51.100.2");
}

TEST(TrustedProxies, TheWalkStopsAfter32Entries) {
  std::string chain = "198.51.100.2";
  for (int i = 1; i <= 40; ++i) chain += ", 10.0.0." + std::to_string(i);
  // From the right, 10.0.0.40 down to 10.0.0.9 are the 32 walked; the client is never reached.
  EXPECT_EQ(client(kPrivate, "10.0.0.5", {chain}), "10.0.0.9");
  std::string short_chain = "198.51.100.2";
  for (int i = 1; i <= 31; ++i) short_chain += ", 10.0.0." + std::to_string(i);
  EXPECT_EQ(client(kPrivate, "10.0.0.5", {short_chain}), "198.51.100.2");  // the 32nd entry
}

TEST(TrustedProxies, ReadsTheHeaderLinesOfARequest) {
  Request req;
  req.headers.emplace("x-forwarded-for", "6.6.6.6, 198.51.100.2");
  req.headers.emplace("Host", "example");
  req.headers.emplace("X-Forwarded-For", "192.168.1.1");
  EXPECT_EQ(kPrivate.client_address_of("10.0.0.5", req.headers), "198.51.100.2");
  EXPECT_EQ(kPrivate.client_address_of("203.0.113.7", req.headers), "203.0.113.7");
}

using test::parse;

TEST(TrustedProxies, IsASettingWithItsVariable) {
  EXPECT_TRUE(parse({}).trusted_proxies.empty());
  EXPECT_TRUE(parse({}, {{"MDN_TRUSTED_PROXIES", "10.0.0.0/8"}}).trusted_proxies.contains("10.1.1.1"));
  const ServerConfig c = parse({"--trusted-proxies", "::1/128"}, {{"MDN_TRUSTED_PROXIES", "10.0.0.0/8"}});
  EXPECT_FALSE(c.trusted_proxies.contains("10.1.1.1"));
  EXPECT_TRUE(c.trusted_proxies.contains("::1"));
  EXPECT_NE(help_text().find("--trusted-proxies (MDN_TRUSTED_PROXIES)"), std::string::npos);
  try {
    parse({"--trusted-proxies", "10.0.0.0/8,10.0.0.300/32"});
    ADD_FAILURE() << "a bad list was accepted";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("--trusted-proxies"), std::string::npos) << what;
    EXPECT_NE(what.find("'10.0.0.300/32'"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace mdn::http
