// Limits::cancel and EncodeOptions::cancel (core/io/document.h): the job's time limit and
// DELETE reach the decoders' and encoders' loops. Every format's decoder asks the observer
// while it reads a mesh of a few thousand elements and stops with CancelledError when told
// to; without a request to stop it decodes as before.
#include <gtest/gtest.h>

#include <string>

#include "core/errors.h"
#include "core/io/document.h"
#include "io_test_support.h"
#include "support/shapes.h"

namespace mdn::io {
namespace {

// Counts the polls; asks to stop from the `stop_at`-th one on (0: never).
class CountingCancel final : public ProgressObserver {
 public:
  explicit CountingCancel(int stop_at) : stop_at_(stop_at) {}
  void on_progress(Stage, double) override {}
  bool cancel_requested() override { return ++polls >= stop_at_ && stop_at_ > 0; }
  int polls = 0;

 private:
  int stop_at_;
};

// A 60 x 60 grid (3,721 vertices, 7,200 triangles) written in `format` by the io writers.
std::string grid_in(Format format) {
  const std::string off = test::off_text(test_io::grid(60));
  if (format == Format::Off) return off;
  EncodeOptions options;
  options.format = format;
  options.compression = format == Format::Drc ? mdn::io::Compression::Draco : mdn::io::Compression::None;
  return decode(off, Format::Off)->encode(options).bytes;
}

class DecoderCancel : public ::testing::TestWithParam<Format> {};

TEST_P(DecoderCancel, StopsWhenAskedAndDecodesOtherwise) {
  const std::string bytes = grid_in(GetParam());
  Limits limits;
  CountingCancel never(0);
  limits.cancel = &never;
  EXPECT_EQ(decode(bytes, GetParam(), limits)->surfaces().front().num_faces(), 7200);

  CountingCancel stop(1);
  limits.cancel = &stop;
  EXPECT_THROW(decode(bytes, GetParam(), limits), CancelledError);
  EXPECT_GE(stop.polls, 1);
}

INSTANTIATE_TEST_SUITE_P(EveryFormat, DecoderCancel,
                         ::testing::Values(Format::Off, Format::Obj, Format::Ply, Format::Stl, Format::Glb, Format::Drc),
                         [](const auto& info) { return std::string(to_string(info.param)); });

TEST(DecoderCancel, TextLoopsAskEveryFewThousandLines) {
  // 3,721 vertex lines and 7,200 face lines: the OFF loops ask once per 4,096 lines.
  const std::string off = test::off_text(test_io::grid(60));
  CountingCancel never(0);
  Limits limits;
  limits.cancel = &never;
  decode(off, Format::Off, limits);
  EXPECT_EQ(never.polls, 2);  // at lines 4,096 and 8,192 of 10,921
  CountingCancel late(2);  // the second poll stops it: within the face lines
  limits.cancel = &late;
  EXPECT_THROW(decode(off, Format::Off, limits), CancelledError);
  EXPECT_EQ(late.polls, 2);
}

TEST(EncoderCancel, SameFormatAndDracoWritersStopWhenAsked) {
  for (Format format : {Format::Off, Format::Ply, Format::Drc, Format::Glb}) {
    SCOPED_TRACE(std::string(to_string(format)));
    auto doc = decode(grid_in(format), format);
    EncodeOptions options;
    CountingCancel stop(1);
    options.cancel = &stop;
    EXPECT_THROW(doc->encode(options).bytes, CancelledError);
    CountingCancel never(0);
    options.cancel = &never;
    EXPECT_FALSE(doc->encode(options).bytes.empty());
  }
}

}  // namespace
}  // namespace mdn::io
