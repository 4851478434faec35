// Decision 100's pieces that decide whether the command-line tool restarts with huge pages
// (tests/integration/cli_test.cpp runs the restart itself).
#include "service/process_memory.h"

#include <gtest/gtest.h>

namespace mdn::service {
namespace {

TEST(HugePages, TheTunableIsAddedOnceAndACallersOwnChoiceStands) {
  EXPECT_EQ(tunables_with_huge_pages(nullptr), "glibc.malloc.hugetlb=1");
  EXPECT_EQ(tunables_with_huge_pages(""), "glibc.malloc.hugetlb=1");
  EXPECT_EQ(tunables_with_huge_pages("glibc.malloc.arena_max=2"), "glibc.malloc.arena_max=2:glibc.malloc.hugetlb=1");
  // Set already, to anything: unchanged (and the restarted process does not restart again).
  EXPECT_EQ(tunables_with_huge_pages("glibc.malloc.hugetlb=1"), std::nullopt);
  EXPECT_EQ(tunables_with_huge_pages("glibc.malloc.hugetlb=0"), std::nullopt);
  EXPECT_EQ(tunables_with_huge_pages("glibc.malloc.arena_max=2:glibc.malloc.hugetlb=2"), std::nullopt);
}

TEST(HugePages, OnlyAKernelThatGivesThemOnRequestCounts) {
  EXPECT_TRUE(huge_pages_on_request("always [madvise] never\n"));
  EXPECT_TRUE(huge_pages_on_request("[always] madvise never\n"));
  EXPECT_FALSE(huge_pages_on_request("always madvise [never]\n"));
  EXPECT_FALSE(huge_pages_on_request(""));  // no such file
}

}  // namespace
}  // namespace mdn::service
