// service/output_files: which .gltf inputs keep their data beside them.
#include <gtest/gtest.h>

#include "service/output_files.h"

namespace mdn::service {
namespace {

TEST(OutputFiles, ExternalUrisAreFoundDataUrisAreNot) {
  EXPECT_FALSE(has_external_uris(R"({"buffers":[{"byteLength":4,"uri":"data:application/octet-stream;base64,AAAAAA=="}]})"));
  EXPECT_FALSE(has_external_uris(R"({"buffers":[{"byteLength":4, "uri" : "data:x"}],"extras":{"text":"\"uri\": a.bin"}})"));
  EXPECT_FALSE(has_external_uris(R"({"extensions":{"X":{"uri":"a.bin"}}})"));  // only buffers and images count
  EXPECT_TRUE(has_external_uris(R"({"buffers":[{"byteLength":4,"uri":"data:,"},{"byteLength":4,"uri":"a.bin"}]})"));
  EXPECT_TRUE(has_external_uris(R"({"images":[{"uri" :  "textures/a.png"}]})"));
  // A key spelled with escapes is still the key "uri".
  EXPECT_TRUE(has_external_uris(R"({"buffers":[{"byteLength":4,"\u0075ri":"a.bin"}]})"));
  EXPECT_FALSE(has_external_uris("{not json"));
}

}  // namespace
}  // namespace mdn::service
