// The SDL display (acquire/src/sdl_display.cc) under SDL's headless "dummy" video driver: it is
// listed, shows exactly the rasterised pattern (read back where the renderer supports it) and
// refuses a display index that does not exist. Then in a real X11 window on an Xvfb server, read
// back from the X server's screen: every dot where the plan says, at its size, intensity and
// gamma, in landscape and portrait screens.

#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>

#include "svbtdf/acquire/pattern_raster.h"
#include "svbtdf/acquire/sdl_display.h"
#include "svbtdf/common/error.h"
#include "x11_screen.h"

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

// An Xvfb server of one screen for the test's lifetime, found through -displayfd (it writes its
// display number when it accepts connections), and SDL pointed at it through DISPLAY.
class XvfbServer {
 public:
  static std::optional<std::string> Find() {
    for (const char* dir : {"/usr/bin", "/usr/local/bin", "/bin"}) {
      const std::string path = std::string(dir) + "/Xvfb";
      if (::access(path.c_str(), X_OK) == 0) return path;
    }
    return std::nullopt;
  }
  // A server that does not start (a display number taken between Xvfb's check and its bind)
  // gets a few attempts, each a fresh server.
  XvfbServer(const std::string& binary, int width, int height) {
    for (int attempt = 0; attempt < 3 && display_.empty(); ++attempt) {
      Stop();
      Start(binary, width, height);
    }
  }
  ~XvfbServer() { Stop(); }
  const std::string& display() const { return display_; }

 private:
  void Start(const std::string& binary, int width, int height) {
    int fds[2];
    if (::pipe(fds) != 0) return;
    pid_ = ::fork();
    if (pid_ == 0) {
      ::close(fds[0]);
      const std::string fd = std::to_string(fds[1]);
      const std::string screen = std::to_string(width) + "x" + std::to_string(height) + "x24";
      ::execl(binary.c_str(), "Xvfb", "-displayfd", fd.c_str(), "-screen", "0", screen.c_str(), "-nolisten", "tcp",
              "-noreset", static_cast<char*>(nullptr));
      ::_exit(127);
    }
    ::close(fds[1]);
    // Xvfb writes the number and then, separately, a newline, and dies ("Cannot write display
    // number to fd N") if the pipe is closed in between: read up to the newline before closing.
    std::string number;
    pollfd ready{fds[0], POLLIN, 0};
    char c = 0;
    while (number.size() < 16 && ::poll(&ready, 1, 15000) == 1 && ::read(fds[0], &c, 1) == 1 && c != '\n') {
      number += c;
    }
    if (c == '\n' && !number.empty()) display_ = ":" + number;
    ::close(fds[0]);
  }
  void Stop() {
    if (pid_ > 0) {
      ::kill(pid_, SIGTERM);
      ::waitpid(pid_, nullptr, 0);
    }
    pid_ = -1;
  }

  pid_t pid_ = -1;
  std::string display_;
};

class SdlOnXvfb : public ::testing::Test {
 protected:
  void SetUp() override {
    binary_ = XvfbServer::Find();
    if (!binary_) GTEST_SKIP() << "Xvfb is not installed (scripts/install-deps.sh installs it): the X11 window test cannot run";
    for (const char* name : {"DISPLAY", "SDL_VIDEODRIVER"}) {
      const char* value = std::getenv(name);
      saved_.emplace_back(name, value ? std::optional<std::string>(value) : std::nullopt);
    }
  }
  void TearDown() override {
    for (const auto& [name, value] : saved_) {
      if (value) setenv(name.c_str(), value->c_str(), 1); else unsetenv(name.c_str());
    }
  }
  // The screen once it shows `expected` (the window is mapped and drawn asynchronously), or the
  // last screen read after two seconds.
  static svbtdf::testing::X11Screen ScreenShowing(const std::string& display, const std::vector<uint8_t>& expected) {
    svbtdf::testing::X11Screen screen;
    for (int attempt = 0; attempt < 100; ++attempt) {
      if (auto read = svbtdf::testing::ReadX11Screen(display)) screen = std::move(*read);
      if (screen.red == expected) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return screen;
  }
  std::optional<std::string> binary_;
  std::vector<std::pair<std::string, std::optional<std::string>>> saved_;
};

// Linear intensity of a code value through the display's gamma.
double Linear(uint8_t code, double gamma) { return std::pow(code / 255.0, gamma); }

// In a landscape and a portrait screen (a monitor turned in the OS): the dot grid one dot at a
// time, the fiducials (some dots lit at once), flat white and the chessboard, each read back from
// the X server and compared with the plan: the same code values pixel for pixel, and each dot's
// centre (the linear-intensity centroid), size (its flux over pi r^2) and intensity (its flux
// over the same disk at full white) where the plan puts them.
TEST_F(SdlOnXvfb, EveryDotIsWhereThePlanSaysAtItsSizeIntensityAndGamma) {
  for (const auto& [width, height] : {std::pair{800, 600}, std::pair{600, 800}}) {
    XvfbServer server(*binary_, width, height);
    ASSERT_FALSE(server.display().empty()) << "Xvfb did not start";
    setenv("DISPLAY", server.display().c_str(), 1);
    setenv("SDL_VIDEODRIVER", "x11", 1);
    SdlDisplayOptions options;
    options.gamma = 2.2;
    SdlDisplay display(0, options);
    const DisplayInfo info = display.Info();
    ASSERT_EQ(info.width_px, width);
    ASSERT_EQ(info.height_px, height);
    const double radius = 3.0, intensity = 0.6;
    double worst_centre = 0.0, worst_flux = 0.0;
    int dots = 0;
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 4; ++col) {
        Pattern dot;
        dot.kind = Pattern::Kind::kDot;
        dot.x_px = 60.0 + col * (width - 120.0) / 3 + 0.25 * col;
        dot.y_px = 80.0 + row * (height - 160.0) / 2 + 0.4 * row;
        dot.dot_radius_px = radius;
        dot.intensity = intensity;
        const double before = MonotonicSeconds();
        const Presentation presentation = display.Show(dot);
        EXPECT_GE(presentation.presented_s, before);
        EXPECT_LE(presentation.presented_s, MonotonicSeconds());
        const std::vector<uint8_t> expected = RasterizePattern(dot, width, height, options.gamma);
        const svbtdf::testing::X11Screen screen = ScreenShowing(server.display(), expected);
        ASSERT_EQ(screen.width, width);
        ASSERT_TRUE(screen.red == expected) << "dot (" << col << ", " << row << ") on the " << width << "x" << height
                                            << " screen differs from the plan's raster";
        double flux = 0, sx = 0, sy = 0;
        for (int y = 0; y < height; ++y) {
          for (int x = 0; x < width; ++x) {
            const double v = Linear(screen.red[static_cast<size_t>(y) * width + x], options.gamma);
            flux += v, sx += v * x, sy += v * y;
          }
        }
        worst_centre = std::max(worst_centre, std::hypot(sx / flux - dot.x_px, sy / flux - dot.y_px));
        worst_flux = std::max(worst_flux, std::abs(flux / (intensity * M_PI * radius * radius) - 1));
        ++dots;
      }
    }
    std::printf("%dx%d: %d dots, centre error at most %.4f px, flux (size x intensity) error at most %.2f%%\n", width,
                height, dots, worst_centre, 100 * worst_flux);
    EXPECT_LT(worst_centre, 0.02);
    EXPECT_LT(worst_flux, 0.01);

    Pattern fiducials;
    fiducials.kind = Pattern::Kind::kAllDots;
    fiducials.all_dots_px = {{100.5, 100.5}, {width - 100.0, 120.0}, {width / 2.0, height - 90.0}};
    fiducials.dot_radius_px = radius;
    Pattern white;
    white.kind = Pattern::Kind::kFlatWhite;
    white.intensity = 0.5;
    Pattern board;
    board.kind = Pattern::Kind::kChessboard;
    board.board_square_px = 40;
    for (const Pattern& pattern : {fiducials, white, board}) {
      display.Show(pattern);
      const std::vector<uint8_t> expected = RasterizePattern(pattern, width, height, options.gamma);
      const svbtdf::testing::X11Screen screen = ScreenShowing(server.display(), expected);
      EXPECT_TRUE(screen.red == expected)
          << "pattern kind " << static_cast<int>(pattern.kind) << " on the " << width << "x" << height << " screen";
      // Half intensity is gamma-encoded on screen: code 255 x 0.5^(1/2.2) = 186, not 128.
      if (pattern.kind == Pattern::Kind::kFlatWhite) {
        EXPECT_EQ(screen.red.at(0), 186);
      }
    }
  }
}

}  // namespace
}  // namespace svbtdf::acquire
