#include "svbtdf/acquire/sdl_display.h"

#include <SDL.h>

#include <algorithm>

#include "svbtdf/acquire/pattern_raster.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/interrupt.h"

namespace svbtdf::acquire {
namespace {

[[noreturn]] void ThrowSdl(const std::string& subject, const std::string& call,
                           const std::string& hint = "") {
  throw common::Error(common::ErrorKind::kHardware, subject, call + " failed: " + SDL_GetError(),
              hint.empty() ? "set SDL_VIDEODRIVER (x11, wayland, kmsdrm) to choose a video driver"
                           : hint);
}

// SDL probes its drivers in turn, and its Wayland probe makes libwayland print "XDG_RUNTIME_DIR
// is invalid or not set" on stderr wherever there is no Wayland session (a console, ssh, CI).
// Where no Wayland socket can be found, ask for the drivers that can work instead; the user's
// SDL_VIDEODRIVER, an environment variable, outranks this default-priority hint.
void SkipWaylandWithoutASession() {
  const char* wayland_display = SDL_getenv("WAYLAND_DISPLAY");
  const bool absolute_socket = wayland_display && wayland_display[0] == '/';
  const char* runtime_dir = SDL_getenv("XDG_RUNTIME_DIR");
  if (absolute_socket || (runtime_dir && runtime_dir[0] != '\0')) return;
  const char* x11_display = SDL_getenv("DISPLAY");
  SDL_SetHintWithPriority(SDL_HINT_VIDEODRIVER, x11_display && x11_display[0] ? "x11" : "kmsdrm", SDL_HINT_DEFAULT);
}

void InitVideo(const std::string& subject) {
  SkipWaylandWithoutASession();
  if (SDL_InitSubSystem(SDL_INIT_VIDEO) != 0) {
    ThrowSdl(subject, "SDL_InitSubSystem(video)",
             "no display server or DRM device; run inside X11/Wayland, on a console with "
             "access to /dev/dri, or set SDL_VIDEODRIVER");
  }
  // Without a display server SDL silently falls back to an invisible off-screen driver; a
  // capture against it would photograph a dark monitor for hours. Only accept it on request.
  const std::string driver = SDL_GetCurrentVideoDriver() ? SDL_GetCurrentVideoDriver() : "";
  const char* requested = SDL_getenv("SDL_VIDEODRIVER");
  if ((driver == "offscreen" || driver == "dummy") && (!requested || driver != requested)) {
    SDL_QuitSubSystem(SDL_INIT_VIDEO);
    throw common::Error(common::ErrorKind::kHardware, subject,
                "SDL found no real display (it fell back to the '" + driver + "' driver)",
                "run inside X11/Wayland or on a console with access to /dev/dri; set "
                "SDL_VIDEODRIVER=" + driver + " only for tests");
  }
}

// SDL reference-counts subsystem initialisation; this pairs one Init with one Quit.
class VideoSubsystem {
 public:
  VideoSubsystem() { InitVideo("sdl"); }
  ~VideoSubsystem() { SDL_QuitSubSystem(SDL_INIT_VIDEO); }
};

DisplayInfo DescribeDisplay(int index, const SdlDisplayOptions& options) {
  SDL_Rect bounds{};
  if (SDL_GetDisplayBounds(index, &bounds) != 0) ThrowSdl("sdl:" + std::to_string(index), "SDL_GetDisplayBounds");
  DisplayInfo info;
  info.id = "sdl:" + std::to_string(index);
  info.width_px = bounds.w;
  info.height_px = bounds.h;
  info.pixel_pitch_mm = options.pixel_pitch_mm;
  info.gamma = options.gamma;
  return info;
}

}  // namespace

std::vector<DisplayInfo> ListSdlDisplays() {
  VideoSubsystem video;
  const int count = SDL_GetNumVideoDisplays();
  if (count < 0) ThrowSdl("sdl", "SDL_GetNumVideoDisplays");
  std::vector<DisplayInfo> displays;
  for (int index = 0; index < count; ++index) displays.push_back(DescribeDisplay(index, {}));
  return displays;
}

std::unique_ptr<Display> OpenSdlDisplay(int index, const SdlDisplayOptions& options) {
  return std::make_unique<SdlDisplay>(index, options);
}

SdlDisplay::SdlDisplay(int index, SdlDisplayOptions options)
    : index_(index), options_(options) {
  if (!(options_.gamma > 0.0)) common::ThrowInvalidInput("sdl:" + std::to_string(index), "gamma must be positive");
  // Keep the pattern up when the operator clicks into a terminal on another monitor.
  SDL_SetHint(SDL_HINT_VIDEO_MINIMIZE_ON_FOCUS_LOSS, "0");
  InitVideo("sdl:" + std::to_string(index));
  try {
    const int count = SDL_GetNumVideoDisplays();
    if (index < 0 || index >= count) {
      throw common::Error(common::ErrorKind::kInvalidInput, "sdl:" + std::to_string(index),
                  "no such display (SDL sees " + std::to_string(count) + ")",
                  "`svbtdf devices` lists the displays");
    }
    info_ = DescribeDisplay(index, options_);
    window_ = SDL_CreateWindow("svbtdf", SDL_WINDOWPOS_CENTERED_DISPLAY(index),
                               SDL_WINDOWPOS_CENTERED_DISPLAY(index), info_.width_px,
                               info_.height_px,
                               SDL_WINDOW_FULLSCREEN_DESKTOP | SDL_WINDOW_BORDERLESS | SDL_WINDOW_SHOWN);
    if (!window_) ThrowSdl(info_.id, "SDL_CreateWindow");
    const Uint32 vsync = options_.vsync ? SDL_RENDERER_PRESENTVSYNC : 0;
    renderer_ = SDL_CreateRenderer(window_, -1, SDL_RENDERER_ACCELERATED | vsync);
    if (!renderer_) renderer_ = SDL_CreateRenderer(window_, -1, SDL_RENDERER_SOFTWARE);
    if (!renderer_) ThrowSdl(info_.id, "SDL_CreateRenderer");
    int width = 0, height = 0;  // in pixels, which differ from bounds on HiDPI outputs
    if (SDL_GetRendererOutputSize(renderer_, &width, &height) != 0) ThrowSdl(info_.id, "SDL_GetRendererOutputSize");
    info_.width_px = width;
    info_.height_px = height;
    texture_ = SDL_CreateTexture(renderer_, SDL_PIXELFORMAT_RGB24, SDL_TEXTUREACCESS_STREAMING,
                                 width, height);
    if (!texture_) ThrowSdl(info_.id, "SDL_CreateTexture");
    SDL_SetTextureBlendMode(texture_, SDL_BLENDMODE_NONE);
    SDL_ShowCursor(SDL_DISABLE);
    SDL_DisplayMode mode{};
    if (SDL_GetCurrentDisplayMode(index, &mode) == 0 && mode.refresh_rate > 0) refresh_period_s_ = 1.0 / mode.refresh_rate;
    Show(Pattern{});  // black until told otherwise
  } catch (...) {
    if (texture_) SDL_DestroyTexture(texture_);
    if (renderer_) SDL_DestroyRenderer(renderer_);
    if (window_) SDL_DestroyWindow(window_);
    SDL_QuitSubSystem(SDL_INIT_VIDEO);
    throw;
  }
}

SdlDisplay::~SdlDisplay() {
  SDL_DestroyTexture(texture_);
  SDL_DestroyRenderer(renderer_);
  SDL_DestroyWindow(window_);
  SDL_ShowCursor(SDL_ENABLE);
  SDL_QuitSubSystem(SDL_INIT_VIDEO);
}

std::string SdlDisplay::RendererName() const {
  SDL_RendererInfo info{};
  SDL_GetRendererInfo(renderer_, &info);
  return info.name ? info.name : "";
}

void SdlDisplay::PumpEvents() {
  SDL_Event event;
  while (SDL_PollEvent(&event)) {
    const bool escape = event.type == SDL_KEYDOWN && event.key.keysym.sym == SDLK_ESCAPE;
    if (event.type == SDL_QUIT || escape) common::SetInterruptRequested(true);
  }
}

void SdlDisplay::Draw() {
  void* pixels = nullptr;
  int pitch = 0;
  if (SDL_LockTexture(texture_, nullptr, &pixels, &pitch) != 0) ThrowSdl(info_.id, "SDL_LockTexture");
  for (int y = 0; y < info_.height_px; ++y) {
    auto* row = static_cast<uint8_t*>(pixels) + static_cast<size_t>(y) * pitch;
    const uint8_t* codes = last_codes_.data() + static_cast<size_t>(y) * info_.width_px;
    for (int x = 0; x < info_.width_px; ++x) row[3 * x] = row[3 * x + 1] = row[3 * x + 2] = codes[x];
  }
  SDL_UnlockTexture(texture_);
  if (SDL_RenderCopy(renderer_, texture_, nullptr, nullptr) != 0) ThrowSdl(info_.id, "SDL_RenderCopy");
}

Presentation SdlDisplay::Show(const Pattern& pattern) {
  last_codes_ = RasterizePattern(pattern, info_.width_px, info_.height_px, options_.gamma);
  PumpEvents();
  Draw();
  // Reading a pixel back waits for the GPU to finish drawing (glFinish-like); checking it
  // catches a render path that alters values (colour management, scaling).
  const auto brightest = std::max_element(last_codes_.begin(), last_codes_.end());
  const int offset = static_cast<int>(brightest - last_codes_.begin());
  SDL_Rect probe{offset % info_.width_px, offset / info_.width_px, 1, 1};
  uint8_t rgba[4] = {};
  SDL_RenderFlush(renderer_);
  if (SDL_RenderReadPixels(renderer_, &probe, SDL_PIXELFORMAT_RGBA32, rgba, 4) == 0 &&
      rgba[0] != *brightest) {
    throw common::Error(common::ErrorKind::kHardware, info_.id,
                "shows code " + std::to_string(rgba[0]) + " where the pattern has " +
                    std::to_string(*brightest),
                "turn off colour management / night light for this output");
  }
  const double submitted = MonotonicSeconds();
  SDL_RenderPresent(renderer_);
  Presentation presentation;
  presentation.presented_s = MonotonicSeconds();
  presentation.vsync_aligned = options_.vsync && refresh_period_s_ > 0;
  if (presentation.vsync_aligned) {
    presentation.missed_frames = static_cast<int>((presentation.presented_s - submitted) / refresh_period_s_);
    missed_frames_ += presentation.missed_frames;
  }
  return presentation;
}

bool SdlDisplay::ReadBackLastFrame(std::vector<uint8_t>* codes) {
  Draw();
  SDL_RenderFlush(renderer_);
  std::vector<uint8_t> rgba(static_cast<size_t>(info_.width_px) * info_.height_px * 4);
  if (SDL_RenderReadPixels(renderer_, nullptr, SDL_PIXELFORMAT_RGBA32, rgba.data(),
                           info_.width_px * 4) != 0) {
    return false;
  }
  codes->resize(static_cast<size_t>(info_.width_px) * info_.height_px);
  for (size_t i = 0; i < codes->size(); ++i) (*codes)[i] = rgba[4 * i];
  return true;
}

}  // namespace svbtdf::acquire
