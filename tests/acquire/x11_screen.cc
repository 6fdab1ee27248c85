#include "x11_screen.h"

#include <X11/Xlib.h>
#include <X11/Xutil.h>

namespace svbtdf::testing {

std::optional<X11Screen> ReadX11Screen(const std::string& name) {
  ::Display* x = XOpenDisplay(name.c_str());
  if (!x) return std::nullopt;
  const int screen = DefaultScreen(x);
  X11Screen out;
  out.width = DisplayWidth(x, screen);
  out.height = DisplayHeight(x, screen);
  XSync(x, False);
  XImage* image = XGetImage(x, RootWindow(x, screen), 0, 0, out.width, out.height, AllPlanes, ZPixmap);
  if (!image) {
    XCloseDisplay(x);
    return std::nullopt;
  }
  int shift = 0;
  while (shift < 32 && !((image->red_mask >> shift) & 1)) ++shift;
  out.red.resize(static_cast<size_t>(out.width) * out.height);
  for (int y = 0; y < out.height; ++y) {
    for (int x_ = 0; x_ < out.width; ++x_) {
      out.red[static_cast<size_t>(y) * out.width + x_] =
          static_cast<uint8_t>((XGetPixel(image, x_, y) & image->red_mask) >> shift);
    }
  }
  XDestroyImage(image);
  XCloseDisplay(x);
  return out;
}

}  // namespace svbtdf::testing
