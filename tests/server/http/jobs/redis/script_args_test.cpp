// The typed arguments of the Redis store's Lua scripts land where the scripts' headers say
// (KEYS[i] is argv[2 + i], ARGV[i] is argv[2 + numkeys + i]), with the fragments each script calls.
#include "server/http/jobs/redis/script_args.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "server/http/jobs/redis/scripts.h"

namespace mdn::http::redis {
namespace {

const std::string& key(const Argv& a, int i) { return a.at(2 + i); }
const std::string& arg(const Argv& a, int i) { return a.at(2 + std::stoi(a.at(2)) + i); }

void expect_keys(const Argv& a, const std::vector<std::string>& keys) {
  ASSERT_EQ(a.at(2), std::to_string(keys.size()));
  for (std::size_t i = 0; i < keys.size(); ++i) EXPECT_EQ(key(a, int(i) + 1), keys[i]) << "KEYS[" << i + 1 << "]";
}

void expect_argv(const Argv& a, const std::vector<std::string>& argv) {
  ASSERT_EQ(a.size(), 3 + std::stoul(a.at(2)) + argv.size());
  for (std::size_t i = 0; i < argv.size(); ++i) EXPECT_EQ(arg(a, int(i) + 1), argv[i]) << "ARGV[" << i + 1 << "]";
}

TEST(RedisScriptArgs, HeartbeatPositionsAreThoseOfItsHeader) {
  const Argv a = BeatArgs{"h", "s", "me", "normal_filter", "0.5", "1-0", "workers"}.to_argv();
  EXPECT_EQ(a[0], "EVAL");
  EXPECT_EQ(a[1], lua_script("beat"));
  expect_keys(a, {"h", "s"});
  expect_argv(a, {"me", "normal_filter", "0.5", "1-0", "workers"});
}

TEST(RedisScriptArgs, FinishKeepsItsUnusedSlotAndCallsTheHelpers) {
  const Argv a = FinishArgs{"h", "i", "s", "r", "r:me", "me", "succeeded", "", "{}", "600000", "99", "1-0", "workers",
                            "123"}
                     .to_argv();
  EXPECT_EQ(a[1], lua_script("finish_helpers") + lua_script("finish"));
  expect_keys(a, {"h", "i", "s", "r", "r:me"});
  expect_argv(a, {"me", "succeeded", "", "{}", "" /* unused */, "600000", "99", "1-0", "workers", "123"});
}

TEST(RedisScriptArgs, SubmitStartHasFourKeysThenStartJobsArgvThenTheJobs) {
  const StartFields start{"me", "5", "3", "workers", "exhausted", "cancelled", "600000", "lost", "mdn:job:"};
  const SubmitFields job{"id1", "42", "off", "{}", "4", "64", "fp", "1", "client:ann", "8"};
  const Argv a = SubmitStartArgs{"s", "h", "i", "idem", start, job}.to_argv();
  EXPECT_EQ(a[1], lua_script("finish_helpers") + lua_script("start_job") + lua_script("submit_job") +
                      lua_script("submit_start"));
  expect_keys(a, {"s", "h", "i", "idem"});
  const std::vector<std::string> start_argv = {"me", "5", "3", "" /* unused */, "workers", "exhausted", "cancelled",
                                               "600000", "lost", "mdn:job:"};
  std::vector<std::string> all = start_argv;
  all.insert(all.end(), {"id1", "42", "off", "{}", "4", "64", "fp", "1", "client:ann", "8"});
  expect_argv(a, all);
  // Taking an entry uses the same ten start fields behind the one key.
  const Argv t = TakeArgs{"s", start}.to_argv();
  expect_keys(t, {"s"});
  expect_argv(t, start_argv);
  std::vector<std::string> taken_over = start_argv;
  taken_over.insert(taken_over.end(), {"1-0", "id1"});
  expect_argv(StartArgs{"s", start, "1-0", "id1"}.to_argv(), taken_over);
}

TEST(RedisScriptArgs, EveryScriptFileIsEmbeddedWithAHeader) {
  for (const embedded::File& f : embedded::lua_scripts()) {
    EXPECT_FALSE(f.bytes.empty()) << f.path;
    EXPECT_EQ(f.bytes.substr(0, 3), "-- ") << f.path << " has no header comment";
  }
  EXPECT_THROW(lua_script("no_such_script"), std::logic_error);
}

}  // namespace
}  // namespace mdn::http::redis
