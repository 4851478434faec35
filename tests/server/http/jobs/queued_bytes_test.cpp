// QueuedBytes (server/http/jobs/queued_bytes.h, decision 79): a client over its share is refused
// 429 before the server's bound answers 503; a lone body always fits; holds give their bytes back
// when released, moved or destroyed, even after the ledger is gone.
#include "server/http/jobs/queued_bytes.h"

#include <gtest/gtest.h>

#include "server/http/problem.h"

namespace mdn::http {
namespace {

Problem refusal(QueuedBytes& q, const std::string& client, std::int64_t bytes) {
  try {
    q.reserve(client, bytes, 7);
  } catch (const HttpError& e) {
    return e.problem();
  }
  ADD_FAILURE() << client << " was not refused " << bytes << " bytes";
  return {};
}

TEST(QueuedBytes, AClientOverItsShareIs429AndTheServerOverItsBoundIs503) {
  QueuedBytes q(100, 40);
  QueuedBytes::Hold a = q.reserve("a", 30, 7);
  const Problem own = refusal(q, "a", 11);
  EXPECT_EQ(own.status, 429);
  EXPECT_EQ(own.type, "over-client-share");
  EXPECT_EQ(own.retry_after_s, 7);
  QueuedBytes::Hold b = q.reserve("b", 40, 7), c = q.reserve("c", 30, 7);
  EXPECT_EQ(q.total(), 100);
  const Problem all = refusal(q, "d", 1);
  EXPECT_EQ(all.status, 503);
  EXPECT_EQ(all.type, "queue-full");
  b.release();
  EXPECT_EQ(q.total(), 60);
  EXPECT_NO_THROW(q.check("d", 40, 7));
}

TEST(QueuedBytes, ALoneBodyLargerThanAShareFits) {
  QueuedBytes q(100, 10);
  QueuedBytes::Hold big = q.reserve("a", 60, 1);
  EXPECT_EQ(refusal(q, "a", 1).status, 429);
  EXPECT_EQ(refusal(q, "b", 50).status, 503);
  QueuedBytes empty(10, 10);
  EXPECT_NO_THROW(empty.reserve("x", 1000, 1));  // nothing else queued: it is admitted
}

TEST(QueuedBytes, HoldsGiveTheirBytesBackOnceWhetherMovedOrOutlivingTheLedger) {
  QueuedBytes::Hold kept;
  {
    QueuedBytes q(100, 100);
    QueuedBytes::Hold h = q.reserve("a", 50, 1);
    QueuedBytes::Hold moved = std::move(h);
    EXPECT_EQ(q.total(), 50);
    h.release();  // moved from: gives nothing back
    EXPECT_EQ(q.total(), 50);
    moved = q.reserve("a", 20, 1);  // the old hold's 50 bytes go back
    EXPECT_EQ(q.total(), 20);
    kept = std::move(moved);
  }
  EXPECT_EQ(kept.bytes(), 20);
  kept.release();  // after its ledger: no crash
  EXPECT_EQ(kept.bytes(), 0);
}

}  // namespace
}  // namespace mdn::http
