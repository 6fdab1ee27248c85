// The SDL display (acquire/src/sdl_display.cc) under SDL's headless "dummy" video driver: it is
// listed, shows exactly the rasterised pattern (read back where the renderer supports it) and
// refuses a display index that does not exist.

#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>

#include "svbtdf/acquire/pattern_raster.h"
#include "svbtdf/acquire/sdl_display.h"
#include "svbtdf/common/error.h"

namespace svbtdf::acquire {
namespace {

class SdlDummyTest : public ::testing::Test {
 protected:
  void SetUp() override { setenv("SDL_VIDEODRIVER", "dummy", /*overwrite=*/0); }
};

TEST_F(SdlDummyTest, ListsTheDummyDisplay) {
  std::vector<DisplayInfo> displays;
  try {
    displays = ListSdlDisplays();
  } catch (const common::Error& error) {
    GTEST_SKIP() << "SDL video unavailable: " << error.what();
  }
  ASSERT_FALSE(displays.empty());
  EXPECT_EQ(displays[0].id, "sdl:0");
  EXPECT_GT(displays[0].width_px, 0);
}

TEST_F(SdlDummyTest, ShowsExactlyTheRasterisedPattern) {
  std::unique_ptr<SdlDisplay> display;
  try {
    display = std::make_unique<SdlDisplay>(0, SdlDisplayOptions{});
  } catch (const common::Error& error) {
    GTEST_SKIP() << "SDL display unavailable: " << error.what();
  }
  const DisplayInfo info = display->Info();
  Pattern dot;
  dot.kind = Pattern::Kind::kDot;
  dot.x_px = info.width_px / 2.0 + 0.3;
  dot.y_px = info.height_px / 3.0 + 0.7;
  dot.dot_radius_px = 4.0;
  dot.intensity = 0.6;
  Pattern board;
  board.kind = Pattern::Kind::kChessboard;
  board.board_square_px = 40;
  for (const Pattern& pattern : {dot, board}) {
    display->Show(pattern);
    std::vector<uint8_t> shown;
    if (!display->ReadBackLastFrame(&shown)) {
      GTEST_SKIP() << "renderer '" << display->RendererName() << "' cannot read pixels back";
    }
    EXPECT_EQ(shown, RasterizePattern(pattern, info.width_px, info.height_px, info.gamma))
        << "renderer " << display->RendererName();
  }
  EXPECT_THROW(display->Show([] { Pattern p; p.kind = Pattern::Kind::kDot; p.dot_radius_px = -1; return p; }()), common::Error);
}

TEST_F(SdlDummyTest, RejectsAMissingDisplayIndex) {
  try {
    SdlDisplay display(99, {});
    FAIL() << "display 99 should not exist";
  } catch (const common::Error& error) {
    if (error.kind() == common::ErrorKind::kHardware) GTEST_SKIP() << "SDL video unavailable: " << error.what();
    EXPECT_EQ(error.kind(), common::ErrorKind::kInvalidInput);
  }
}

}  // namespace
}  // namespace svbtdf::acquire
