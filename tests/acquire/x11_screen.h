#pragma once
// Test support: the screen of an X server as grey code values, read with XGetImage of the root
// window (what a monitor on that server shows, whoever drew it). Kept apart from the tests so
// that Xlib's macros (None, Bool, Status ...) stay out of them.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace svbtdf::testing {

struct X11Screen {
  int width = 0, height = 0;
  std::vector<uint8_t> red;  // row-major, the red channel's 8-bit value
};

// nullopt when the display cannot be opened.
std::optional<X11Screen> ReadX11Screen(const std::string& display);

}  // namespace svbtdf::testing
