#pragma once
// SDL2 display-dot generator: a full-screen borderless window on one monitor showing the
// patterns of RasterizePattern (pattern_raster.h). SDL picks the video driver (X11, Wayland,
// KMSDRM on a bare console); SDL_VIDEODRIVER overrides it. SDL video must be driven from the
// thread that opened the display (the main thread on macOS-like backends).

#include <memory>
#include <string>
#include <vector>

#include "svbtdf/acquire/display.h"

struct SDL_Window;
struct SDL_Renderer;
struct SDL_Texture;

namespace svbtdf::acquire {

struct SdlDisplayOptions {
  double gamma = 2.2;           // the monitor's transfer exponent (measure it for real work)
  double pixel_pitch_mm = 0.0;  // from the monitor's datasheet; SDL's DPI is often a fiction
  bool vsync = true;
};

// Every display SDL can see, as "sdl:N". Throws Error(kHardware) when SDL's video subsystem
// cannot start (no X11/Wayland session and no DRM access).
std::vector<DisplayInfo> ListSdlDisplays();
std::unique_ptr<Display> OpenSdlDisplay(int index, const SdlDisplayOptions& options = {});

class SdlDisplay : public Display {
 public:
  SdlDisplay(int index, SdlDisplayOptions options);
  ~SdlDisplay() override;
  SdlDisplay(const SdlDisplay&) = delete;
  SdlDisplay& operator=(const SdlDisplay&) = delete;

  DisplayInfo Info() const override { return info_; }
  // Rasterises, uploads and draws the pattern, waits for the GPU by reading one pixel back
  // (and checks it), then presents (blocking on vsync where the driver does). Escape or
  // closing the window requests an interrupt, so a capture stops cleanly and can resume.
  // SDL2 gives no swap timestamps: with vsync, SDL_RenderPresent returns at the swap, so the time
  // it returns is the presentation (Psychtoolbox's fallback); a return more than a refresh after
  // the call counts the refreshes missed. Without vsync the time is only when it returned.
  Presentation Show(const Pattern& pattern) override;
  // Refreshes missed since the display opened.
  int missed_frames() const { return missed_frames_; }

  // For tests: draws the last pattern again into the back buffer and reads it back as grey
  // code values (the red channel). Returns false when the renderer cannot read pixels.
  bool ReadBackLastFrame(std::vector<uint8_t>* codes);
  std::string RendererName() const;

 private:
  void Draw();
  void PumpEvents();

  int index_;
  SdlDisplayOptions options_;
  DisplayInfo info_;
  SDL_Window* window_ = nullptr;
  SDL_Renderer* renderer_ = nullptr;
  SDL_Texture* texture_ = nullptr;
  std::vector<uint8_t> last_codes_;
  double refresh_period_s_ = 0.0;  // 0: the mode does not say
  int missed_frames_ = 0;
};

}  // namespace svbtdf::acquire
