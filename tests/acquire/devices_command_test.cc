// `svbtdf devices` end to end: a backend that cannot start is reported and the command still
// succeeds with a complete listing.

#include <gtest/gtest.h>

#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

namespace {

std::string RunCommand(const std::string& command, int* status) {
  std::string output;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return output;
  char buffer[4096];
  while (size_t n = fread(buffer, 1, sizeof buffer, pipe)) output.append(buffer, n);
  *status = pclose(pipe);
  return output;
}

TEST(DevicesCommandTest, ReportsABrokenBackendWithoutFailing) {
  int status = -1;
  const std::string output = RunCommand(
      std::string("SDL_VIDEODRIVER=no-such-driver ") + SVBTDF_CLI_PATH + " devices --json 2>/dev/null",
      &status);
  ASSERT_EQ(status, 0) << output;
  const auto listing = nlohmann::json::parse(output);
  EXPECT_NE(listing["backends"]["sdl"].get<std::string>().find("SDL_InitSubSystem"), std::string::npos)
      << listing.dump();
  EXPECT_TRUE(listing["backends"].contains("v4l2"));
  EXPECT_TRUE(listing["backends"].contains("libcamera"));
  EXPECT_TRUE(listing["backends"].contains("gphoto2"));
  EXPECT_TRUE(listing["cameras"].is_array());
}

TEST(DevicesCommandTest, ListsTheDummyDisplayWhenAskedFor) {
  int status = -1;
  const std::string output =
      RunCommand(std::string("SDL_VIDEODRIVER=dummy ") + SVBTDF_CLI_PATH + " devices 2>/dev/null", &status);
  ASSERT_EQ(status, 0) << output;
  EXPECT_NE(output.find("sdl:0"), std::string::npos) << output;
}

// On a console, over ssh or in CI there is no Wayland session: SDL's Wayland probe made libwayland
// print "XDG_RUNTIME_DIR is invalid or not set in the environment" above svbtdf's own listing.
TEST(DevicesCommandTest, PrintsNothingButItsListingWithoutADisplayServer) {
  int status = -1;
  const std::string output = RunCommand(std::string("env -u XDG_RUNTIME_DIR -u WAYLAND_DISPLAY -u DISPLAY -u SDL_VIDEODRIVER ") +
                                            SVBTDF_CLI_PATH + " devices 2>&1",
                                        &status);
  ASSERT_EQ(status, 0) << output;
  EXPECT_EQ(output.find("XDG_RUNTIME_DIR"), std::string::npos) << output;
  EXPECT_NE(output.find("sdl (displays)"), std::string::npos) << output;
}

}  // namespace
