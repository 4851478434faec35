// meshdenoise-server's configuration: defaults, then MDN_* variables, then flags; bad values
// refused with the setting named; --queue parsed once into a typed address.
#include "server/http/config.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <thread>

#include <map>
#include <string>
#include <vector>

#include "core/io/document.h"
#include "server/service_parts.h"
#include "parse_config.h"

namespace mdn::http {
namespace {

using test::parse;

std::string error_of(const std::vector<std::string>& args, const std::map<std::string, std::string>& env = {}) {
  try {
    parse(args, env);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(Config, FlagsWinOverTheEnvironmentWhichWinsOverDefaults) {
  EXPECT_EQ(parse({}).port, 8080);
  EXPECT_EQ(parse({}, {{"MDN_PORT", "9000"}}).port, 9000);
  EXPECT_EQ(parse({"--port", "9100"}, {{"MDN_PORT", "9000"}}).port, 9100);
  EXPECT_EQ(parse({"--port=9200"}, {{"MDN_PORT", "9000"}}).port, 9200);
  // Each setting on its own: the environment sets one, a flag another.
  const ServerConfig c = parse({"--workers", "3"}, {{"MDN_QUEUE_CAPACITY", "7"}, {"MDN_WORKERS", "9"}});
  EXPECT_EQ(c.workers, 3);
  EXPECT_EQ(c.queue_capacity, 7);
}

TEST(Config, ByteCountsTakeSuffixes) {
  EXPECT_EQ(parse({"--max-body", "2M"}).max_body_bytes, std::int64_t{2} << 20);
  EXPECT_EQ(parse({"--max-body", "64k"}).max_body_bytes, std::int64_t{64} << 10);
}

TEST(Config, BadValuesAreRefusedNamingTheSetting) {
  EXPECT_NE(error_of({"--port", "70000"}).find("--port"), std::string::npos);
  EXPECT_NE(error_of({"--port", "80x"}).find("expected an integer"), std::string::npos);
  EXPECT_NE(error_of({}, {{"MDN_PORT", "-1"}}).find("MDN_PORT"), std::string::npos);
  EXPECT_NE(error_of({"--job-time-limit", "0"}).find("--job-time-limit"), std::string::npos);  // (0, 1e6]
  EXPECT_NE(error_of({"--no-such-flag", "1"}).find("unknown flag"), std::string::npos);
  EXPECT_NE(error_of({"--port"}).find("needs a value"), std::string::npos);
  EXPECT_NE(error_of({"--queue", "postgres://db"}).find("--queue"), std::string::npos);
  EXPECT_NE(error_of({"--queue", "redis://host/16"}).find("Redis database"), std::string::npos);
  EXPECT_NE(error_of({"--queue", "redis://host:0"}).find("Redis port"), std::string::npos);
}

TEST(Config, QueueIsParsedOnceIntoAnAddress) {
  EXPECT_FALSE(parse({}).queue.has_value());
  EXPECT_FALSE(parse({"--queue", "memory"}).queue.has_value());
  const ServerConfig c = parse({}, {{"MDN_QUEUE", "redis://:s3cret@cache.internal:6380/2"}});
  ASSERT_TRUE(c.queue.has_value());
  EXPECT_EQ(c.queue->host, "cache.internal");
  EXPECT_EQ(c.queue->port, 6380);
  EXPECT_EQ(c.queue->db, 2);
  EXPECT_EQ(c.queue->password, "s3cret");
  const RedisAddress v6 = parse_redis_url("redis://[::1]");
  EXPECT_EQ(v6.host, "::1");
  EXPECT_EQ(v6.port, 6379);
  EXPECT_EQ(v6.db, 0);
  EXPECT_EQ(parse_redis_url("redis://user:pw@h").password, "pw");
}

TEST(Config, TheQueueIsShownWithoutItsPassword) {
  EXPECT_EQ(show_queue_setting(std::nullopt), "memory");
  const std::string shown = show_queue_setting(parse_redis_url("redis://:s3cret@cache:6380/2"));
  EXPECT_EQ(shown, "redis://(credentials)@cache:6380/2");
  EXPECT_EQ(show_queue_setting(parse_redis_url("redis://[::1]:7000")), "redis://[::1]:7000/0");
}

TEST(Config, RedisBoundsTheBodyAtWhatItCanStore) {
  EXPECT_EQ(parse({"--max-body", "1G"}).max_body_bytes, std::int64_t{1} << 30);  // memory: allowed
  EXPECT_NE(error_of({"--max-body", "1G", "--queue", "redis://h"}).find("512M"), std::string::npos);
}

TEST(Config, DecoderLimitsDefaultToTheDecodersOwnAndReachTheQueue) {
  const ServerConfig defaults = parse({});
  const io::Limits io_defaults;
  EXPECT_EQ(defaults.max_decoded_bytes, io_defaults.max_decoded_bytes);
  EXPECT_EQ(defaults.max_json_depth, io_defaults.max_json_depth);
  EXPECT_EQ(defaults.max_nodes, io_defaults.max_nodes);
  EXPECT_EQ(defaults.max_accessors, io_defaults.max_accessors);
  const ServerConfig c = parse({"--max-decoded-bytes", "64M", "--max-json-depth", "32", "--max-nodes=500"},
                               {{"MDN_MAX_ACCESSORS", "2000"}, {"MDN_MAX_NODES", "7"}});
  const io::Limits limits = make_pool_options(c).limits;
  EXPECT_EQ(limits.max_decoded_bytes, std::int64_t{64} << 20);
  EXPECT_EQ(limits.max_json_depth, 32);
  EXPECT_EQ(limits.max_nodes, 500);  // the flag wins over MDN_MAX_NODES
  EXPECT_EQ(limits.max_accessors, 2000);
}

TEST(Config, BadDecoderLimitsAreRefusedNamingTheSetting) {
  EXPECT_NE(error_of({"--max-decoded-bytes", "1000"}).find("--max-decoded-bytes"), std::string::npos);  // below 1M
  EXPECT_NE(error_of({"--max-json-depth", "0"}).find("--max-json-depth"), std::string::npos);
  EXPECT_NE(error_of({"--max-json-depth", "20000"}).find("outside [1, 1000]"), std::string::npos);
  EXPECT_NE(error_of({"--max-nodes", "-5"}).find("--max-nodes"), std::string::npos);
  EXPECT_NE(error_of({}, {{"MDN_MAX_ACCESSORS", "many"}}).find("MDN_MAX_ACCESSORS"), std::string::npos);
}

TEST(Config, BodyStallTimeoutIsASettingOfItsOwn) {
  EXPECT_EQ(parse({}).body_stall_timeout_s, 10);
  EXPECT_EQ(parse({"--body-stall-timeout", "2.5"}).body_stall_timeout_s, 2.5);
  EXPECT_EQ(parse({}, {{"MDN_BODY_STALL_TIMEOUT", "4"}}).body_stall_timeout_s, 4);
  EXPECT_NE(error_of({"--body-stall-timeout", "0"}).find("--body-stall-timeout"), std::string::npos);
}

TEST(Config, IoThreadsDefaultToTheMachine) {
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  EXPECT_EQ(parse({}).io_threads, 0);
  EXPECT_EQ(parse({}).effective_io_threads(), std::max(8, 4 * int(cores)));
  EXPECT_EQ(parse({"--io-threads", "16"}).effective_io_threads(), 16);
  EXPECT_NE(error_of({"--io-threads", "2"}).find("below 4"), std::string::npos);
  EXPECT_NE(help_text().find("0 = 4 per core, at least 8; default: 0 ("), std::string::npos) << help_text();
}

TEST(Config, ConnectionSettingsHaveTheirDefaultsAndRanges) {
  const ServerConfig c = parse({});
  EXPECT_EQ(c.header_timeout_s, 10);
  EXPECT_EQ(c.body_timeout_s, 300);
  EXPECT_EQ(c.max_connections_per_client, 64);
  EXPECT_EQ(c.max_connections, 2048);
  EXPECT_EQ(c.sync_start_timeout_s, 30);
  const ServerConfig set = parse({"--header-timeout", "2", "--body-timeout", "60", "--max-connections-per-client", "8",
                                  "--max-connections", "100", "--sync-start-timeout", "5"});
  EXPECT_EQ(set.header_timeout_s, 2);
  EXPECT_EQ(set.body_timeout_s, 60);
  EXPECT_EQ(set.max_connections_per_client, 8);
  EXPECT_EQ(set.max_connections, 100);
  EXPECT_EQ(set.sync_start_timeout_s, 5);
  EXPECT_NE(error_of({"--header-timeout", "0"}).find("--header-timeout"), std::string::npos);
  EXPECT_NE(error_of({"--max-connections-per-client", "0"}).find("--max-connections-per-client"), std::string::npos);
}

TEST(Config, ApiKeysAreNameKeyLines) {
  const auto keys = parse_api_keys("# stations\n\nstation-a:0123456789abcdef\r\nb.2_x:key-without-spaces!\n");
  ASSERT_EQ(keys.size(), 2u);
  EXPECT_EQ(keys[0].name, "station-a");
  EXPECT_EQ(keys[0].key, "0123456789abcdef");  // CR stripped
  auto error = [](const std::string& text) {
    try {
      parse_api_keys(text);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error("a:0123456789abcdef\nnocolon\n").find("line 2"), std::string::npos);
  EXPECT_NE(error("a:short\n").find("16 to 256"), std::string::npos);
  EXPECT_NE(error("bad name:0123456789abcdef\n").find("name"), std::string::npos);
  EXPECT_NE(error("a:0123456789abcdef\na:fedcba9876543210\n").find("repeats"), std::string::npos);
  EXPECT_NE(error("a:0123456789abcdef\nb:0123456789abcdef\n").find("repeats"), std::string::npos);
  EXPECT_NE(error("# nothing\n").find("no keys"), std::string::npos);
  EXPECT_NE(error_of({"--api-keys", "/nonexistent/keys"}).find("cannot read"), std::string::npos);
}

TEST(Config, SharesDefaultToFractionsOfTheStoreAndTheMachine) {
  const ServerConfig c = parse({});
  EXPECT_EQ(c.effective_client_max_stored_jobs(), 256);  // a quarter of 1,024
  EXPECT_EQ(parse({"--max-stored-jobs", "3"}).effective_client_max_stored_jobs(), 1);
  const std::int64_t memory = memory_available_to_process();
  ASSERT_GT(memory, 0);
  EXPECT_EQ(c.effective_max_queued_bytes(), memory / 4);
  EXPECT_EQ(c.effective_client_max_queued_bytes(), std::min(c.max_body_bytes, memory / 16));
  const ServerConfig set = parse({"--client-max-stored-jobs", "5", "--max-queued-bytes", "1G", "--client-max-queued-bytes", "64M"});
  EXPECT_EQ(set.effective_client_max_stored_jobs(), 5);
  EXPECT_EQ(set.effective_max_queued_bytes(), std::int64_t{1} << 30);
  EXPECT_EQ(set.effective_client_max_queued_bytes(), std::int64_t{64} << 20);
  EXPECT_EQ(parse({"--max-queued-bytes", "100M"}).effective_client_max_queued_bytes(), std::int64_t{25} << 20);
  EXPECT_NE(error_of({"--client-max-stored-jobs", "-1"}).find("--client-max-stored-jobs"), std::string::npos);
}

TEST(Config, TheBodyRateFloorAndItsGraceAreSettings) {
  EXPECT_EQ(parse({}).body_min_rate, 500);
  EXPECT_EQ(parse({}).body_rate_grace_s, 10);
  const ServerConfig set = parse({"--body-min-rate", "0", "--body-rate-grace", "2.5"});
  EXPECT_EQ(set.body_min_rate, 0);
  EXPECT_EQ(set.body_rate_grace_s, 2.5);
  EXPECT_EQ(parse({}, {{"MDN_BODY_MIN_RATE", "2000"}}).body_min_rate, 2000);
  EXPECT_NE(error_of({"--body-min-rate", "-1"}).find("--body-min-rate"), std::string::npos);
}

TEST(Config, HelpNamesEveryFlagWithItsVariable) {
  const std::string help = help_text();
  for (const char* s : {"--port (MDN_PORT)", "--queue (MDN_QUEUE)", "--auth-token (MDN_AUTH_TOKEN)",
                        "--max-decoded-bytes (MDN_MAX_DECODED_BYTES)", "--max-json-depth (MDN_MAX_JSON_DEPTH)",
                        "--max-nodes (MDN_MAX_NODES)", "--max-accessors (MDN_MAX_ACCESSORS)",
                        "--body-stall-timeout (MDN_BODY_STALL_TIMEOUT)", "--api-keys (MDN_API_KEYS)",
                        "--header-timeout (MDN_HEADER_TIMEOUT)", "--body-timeout (MDN_BODY_TIMEOUT)",
                        "--max-connections-per-client (MDN_MAX_CONNECTIONS_PER_CLIENT)", "--sync-start-timeout (MDN_SYNC_START_TIMEOUT)",
                        "--client-max-stored-jobs (MDN_CLIENT_MAX_STORED_JOBS)", "--max-queued-bytes (MDN_MAX_QUEUED_BYTES)",
                        "--client-max-queued-bytes (MDN_CLIENT_MAX_QUEUED_BYTES)", "--body-min-rate (MDN_BODY_MIN_RATE)",
                        "--body-rate-grace (MDN_BODY_RATE_GRACE)"})
    EXPECT_NE(help.find(s), std::string::npos) << s;
}

}  // namespace
}  // namespace mdn::http
