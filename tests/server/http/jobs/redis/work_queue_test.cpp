// The slots -> finisher hand-over of the Redis store: first in, first out; close() drains.
#include "server/http/jobs/redis/work_queue.h"

#include <gtest/gtest.h>

#include <string>
#include <thread>
#include <vector>

namespace mdn::http::redis {
namespace {

TEST(WorkQueue, ItemsComeOutInOrderAcrossThreads) {
  WorkQueue<int> q;
  std::vector<int> seen;
  std::thread consumer([&] {
    while (auto v = q.pop()) seen.push_back(*v);
  });
  for (int i = 0; i < 100; ++i) q.push(i);
  q.close();
  consumer.join();
  ASSERT_EQ(seen.size(), 100u);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(seen[std::size_t(i)], i);
}

TEST(WorkQueue, CloseLetsWhatIsQueuedOutFirst) {
  WorkQueue<std::string> q;
  q.push("a");
  q.push("b");
  q.close();
  EXPECT_EQ(q.pop(), "a");
  EXPECT_EQ(q.pop(), "b");
  EXPECT_EQ(q.pop(), std::nullopt);
}

}  // namespace
}  // namespace mdn::http::redis
