// The Redis store's recent-results cache: bounded by bytes and places, oldest out first.
#include "server/http/jobs/redis/recent_results.h"

#include <gtest/gtest.h>

namespace mdn::http::redis {
namespace {

TEST(RecentResults, KeepsWhatWasAddedUntilErased) {
  RecentResults cache;
  cache.add("a", "100", "bytes of a");
  const auto a = cache.find("a");
  ASSERT_TRUE(a);
  EXPECT_EQ(a->finished_ms, "100");
  EXPECT_EQ(*a->bytes, "bytes of a");
  EXPECT_FALSE(cache.find("b"));
  cache.erase("a");
  EXPECT_FALSE(cache.find("a"));
  EXPECT_EQ(cache.total_bytes(), 0u);
}

TEST(RecentResults, ReAddingAJobReplacesItsEntry) {
  RecentResults cache;
  cache.add("a", "1", "first");
  cache.add("a", "2", "second run");
  EXPECT_EQ(cache.find("a")->finished_ms, "2");
  EXPECT_EQ(cache.total_bytes(), std::string("second run").size());
}

TEST(RecentResults, TheOldestGoFirstBeyondTheByteBudget) {
  RecentResults cache({.bytes = 100, .places = 1000});
  for (const char* id : {"a", "b", "c", "d", "e"}) cache.add(id, "1", std::string(25, 'x'));
  EXPECT_FALSE(cache.find("a"));  // 125 bytes: the first is out
  for (const char* id : {"b", "c", "d", "e"}) EXPECT_TRUE(cache.find(id)) << id;
  EXPECT_EQ(cache.total_bytes(), 100u);
}

TEST(RecentResults, AResultOverAQuarterOfTheBudgetIsNotKept) {
  RecentResults cache({.bytes = 100, .places = 1000});
  cache.add("small", "1", std::string(25, 'x'));
  cache.add("large", "1", std::string(26, 'x'));
  EXPECT_TRUE(cache.find("small"));
  EXPECT_FALSE(cache.find("large"));
}

TEST(RecentResults, PlacesOfErasedEntriesCountSoTheOrderStaysBounded) {
  RecentResults cache({.bytes = 1000, .places = 3});
  cache.add("a", "1", "x");
  cache.erase("a");
  cache.add("b", "1", "x");
  cache.add("c", "1", "x");
  cache.add("d", "1", "x");  // a's place is the fourth: it goes, b stays
  EXPECT_TRUE(cache.find("b"));
  cache.add("e", "1", "x");  // now b is the oldest of four places
  EXPECT_FALSE(cache.find("b"));
  for (const char* id : {"c", "d", "e"}) EXPECT_TRUE(cache.find(id)) << id;
}

}  // namespace
}  // namespace mdn::http::redis
